#include "model/grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "mpi/decomposition.hpp"
#include "dpsm/dpsm.h"
#include "structured/relax_to_rest.hpp"
#include "structured/tiled_sweep.hpp"

namespace dpsm {

double bed_film(const Grid &grid) {
    const Geometry &geo = grid.geometry();
    const double spacing = geo.dim == 2 ? std::min(geo.dx, geo.dy) : geo.dx;
    return grid.rest_tolerance() * std::tan(grid.min_repose_angle()) * spacing;
}

Grid::Grid(const Geometry &geometry)
    : geometry_(geometry),
      repose_angle_(DPSM_DEFAULT_REPOSE_ANGLE),
      tan_repose_(std::tan(DPSM_DEFAULT_REPOSE_ANGLE)),
      mobility_(DPSM_DEFAULT_MOBILITY),
      rest_tolerance_(DPSM_DEFAULT_REST_TOLERANCE),
      max_substeps_(DPSM_DEFAULT_MAX_SUBSTEPS),
      heights_(static_cast<std::size_t>(geometry.cells()), 0.0),
      residuals_(static_cast<std::size_t>(geometry.cells()), 0.0f),
      kinds_(static_cast<std::size_t>(geometry.cells()), kSand),
      rate_(geometry.dim == 1 ? static_cast<std::size_t>(geometry.cells()) : 0, 0.0),
      scheme_(geometry.dim == 2 ? kIsotropic : kPairwise) {
    if (geometry.tiled()) {
        active_ = std::make_unique<ActiveSet>(geometry.nx, geometry.ny);
        active_->refresh_masks(*this);
    }
    if (geometry.is_mesh()) {
        mesh_activity_ = std::make_unique<MeshActivity>();
        mesh_activity_->hot.assign(static_cast<std::size_t>(geometry.cells()), 0);
    }
}

Grid::~Grid() = default;

void Grid::set_decomposition(std::unique_ptr<Decomposition> decomposition) {
    decomposition_ = std::move(decomposition);
}

double Grid::global_sum(double local) const { return decomposition_ ? decomposition_->sum(local) : local; }

TiledWorkspace &Grid::tiled_workspace() {
    if (!tiled_) tiled_ = std::make_unique<TiledWorkspace>();
    return *tiled_;
}

RelaxWorkspace &Grid::relax_workspace() {
    if (!relax_) relax_ = std::make_unique<RelaxWorkspace>(heights_.size(), static_cast<std::size_t>(active_->tiles()));
    return *relax_;
}

void Grid::set_repose_angle(double theta) {
    repose_angle_ = theta;
    tan_repose_ = std::tan(theta);
    touched_everywhere();
}

double Grid::sand_mass(const double *values) const {
    CompensatedSum sum;
    for (std::size_t c = 0; c < kinds_.size(); ++c)
        if (kinds_[c] == kSand) sum.add(values[c] * geometry_.cell_area(static_cast<std::int64_t>(c)));
    return sum.value();
}

double Grid::total_mass() const { return sand_mass(heights_.data()); }

double Grid::sand_mass_change(const double *from, const double *to, const CellBox &within) const {
    CompensatedSum change;
    const std::int64_t nx = geometry_.nx;
    const std::int64_t i0 = std::max<std::int64_t>(within.i0, 0), i1 = std::min(within.i1, nx);
    const std::int64_t j0 = std::max<std::int64_t>(within.j0, 0), j1 = std::min(within.j1, geometry_.ny);
    for (std::int64_t j = j0; j < j1; ++j)
        for (std::int64_t c = i0 + nx * j; c < i1 + nx * j; ++c)
            if (kinds_[c] == kSand && to[c] != from[c]) change.add((to[c] - from[c]) * geometry_.cell_area(c));
    return change.value();
}

void Grid::write_heights(const Block &block, const double *values, bool add) {
    // Book the difference cell by cell so that a host that changes a few cells
    // of a large pile gets the change exactly, not a difference of two large sums.
    CompensatedSum change;
    for (std::int64_t j = 0; j < block.nj; ++j)
        for (std::int64_t i = 0; i < block.ni; ++i) {
            const std::int64_t c = (block.i0 + i) + geometry_.nx * (block.j0 + j);
            const double v = values[i + block.ni * j];
            const double next = add ? heights_[c] + v : v;
            if (kinds_[c] == kSand) change.add((next - heights_[c]) * geometry_.cell_area(c));
            // On a mesh only the cells that change, and those across their faces, wake.
            if (mesh_activity_ && (next != heights_[c] || residuals_[c] != 0.0f))
                mesh_activity_->wake_around(*geometry_.mesh, c);
            heights_[c] = next;
            residuals_[c] = 0.0f;
        }
    ledger_.external.add(change.value());
    ++heights_version_;
    if (open_cells_ > 0) update_open_levels();
    if (active_) active_->mark_block(block.i0, block.j0, block.ni, block.nj);
    if (tiled_ && active_) {
        CellBox box;
        box.add(block.i0, block.i0 + block.ni, block.j0, block.j0 + block.nj);
        tiled_workspace_changed(*tiled_, *active_, box);
    }
}

void Grid::set_heights_between_sweeps(const double *y, const CellBox &within) {
    const std::int64_t nx = geometry_.nx, ny = geometry_.ny, side = ActiveSet::kTile;
    const std::int64_t wi0 = std::max<std::int64_t>(within.i0, 0), wi1 = std::min(within.i1, nx);
    const std::int64_t wj0 = std::max<std::int64_t>(within.j0, 0), wj1 = std::min(within.j1, ny);
    if (wi0 >= wi1 || wj0 >= wj1) return;
    for (std::int64_t tj = wj0 - wj0 % side; tj < wj1; tj += side)
        for (std::int64_t ti = wi0 - wi0 % side; ti < wi1; ti += side) {
            // Per tile, so that a pile in one corner wakes only its own cells.
            const std::int64_t i_begin = std::max(ti, wi0), i_end = std::min(ti + side, wi1);
            const std::int64_t j_begin = std::max(tj, wj0), j_end = std::min(tj + side, wj1);
            std::int64_t i0 = nx, i1 = -1, j0 = ny, j1 = -1;
            for (std::int64_t j = j_begin; j < j_end; ++j) {
                const double *row_y = y + nx * j;
                double *row_h = heights_.data() + nx * j;
                float *row_r = residuals_.data() + nx * j;
                auto differs = [&](std::int64_t i) { return row_h[i] != row_y[i] || row_r[i] != 0.0f; };
                // The first and the last cell that differ; those between are
                // simply overwritten (where they agree, with the same values).
                std::int64_t first = i_begin;
                while (first < i_end && !differs(first)) ++first;
                if (first == i_end) continue;
                std::int64_t last = i_end - 1;
                while (!differs(last)) --last;
                for (std::int64_t i = first; i <= last; ++i) {
                    row_h[i] = row_y[i];
                    row_r[i] = 0.0f;
                }
                i0 = std::min(i0, first);
                i1 = std::max(i1, last);
                j0 = std::min(j0, j);
                j1 = j;
            }
            if (i1 < 0) continue;
            CellBox box;
            box.add(i0, i1 + 1, j0, j1 + 1);
            if (active_) active_->mark_block(box.i0, box.j0, box.i1 - box.i0, box.j1 - box.j0);
            if (tiled_ && active_) tiled_workspace_changed(*tiled_, *active_, box);
        }
}

void Grid::copy_heights_between_sweeps(const double *y, const CellBox &within) {
    const std::int64_t nx = geometry_.nx, ny = geometry_.ny, side = ActiveSet::kTile;
    const std::int64_t wi0 = std::max<std::int64_t>(within.i0, 0), wi1 = std::min(within.i1, nx);
    const std::int64_t wj0 = std::max<std::int64_t>(within.j0, 0), wj1 = std::min(within.j1, ny);
    if (wi0 >= wi1 || wj0 >= wj1) return;
    for (std::int64_t j = wj0; j < wj1; ++j)
        std::copy(y + nx * j + wi0, y + nx * j + wi1, heights_.data() + nx * j + wi0);
    // Per tile, as the host's edits are.
    for (std::int64_t tj = wj0 - wj0 % side; tj < wj1; tj += side)
        for (std::int64_t ti = wi0 - wi0 % side; ti < wi1; ti += side) {
            CellBox box;
            box.add(std::max(ti, wi0), std::min(ti + side, wi1), std::max(tj, wj0), std::min(tj + side, wj1));
            if (active_) active_->mark_block(box.i0, box.j0, box.i1 - box.i0, box.j1 - box.j0);
            if (tiled_ && active_) tiled_workspace_changed(*tiled_, *active_, box);
        }
}

Grid::SavedResiduals Grid::drop_residuals() {
    SavedResiduals saved;
    const CellBox box = residual_bounds_.grown_within(0, CellBox{0, geometry_.nx, 0, geometry_.ny});
    saved.box = box;
    if (!box.empty()) {
        saved.values.reserve(static_cast<std::size_t>((box.i1 - box.i0) * (box.j1 - box.j0)));
        for (std::int64_t j = box.j0; j < box.j1; ++j)
            saved.values.insert(saved.values.end(), residuals_.begin() + (box.i0 + geometry_.nx * j),
                                residuals_.begin() + (box.i1 + geometry_.nx * j));
    }
    set_heights_between_sweeps(heights_.data(), residual_bounds_);
    residual_bounds_ = CellBox{};
    return saved;
}

void Grid::restore_residuals(const SavedResiduals &saved) {
    const CellBox &box = saved.box;
    if (box.empty()) return;
    const std::int64_t width = box.i1 - box.i0;
    for (std::int64_t j = box.j0; j < box.j1; ++j)
        std::copy_n(saved.values.begin() + width * (j - box.j0), width,
                    residuals_.begin() + (box.i0 + geometry_.nx * j));
    residual_bounds_.add(box);
    if (active_) active_->mark_block(box.i0, box.j0, width, box.j1 - box.j0);
    if (tiled_ && active_) tiled_workspace_changed(*tiled_, *active_, box);
}

void Grid::read_heights(const Block &block, double *values) const {
    for (std::int64_t j = 0; j < block.nj; ++j)
        for (std::int64_t i = 0; i < block.ni; ++i)
            values[i + block.ni * j] = heights_[(block.i0 + i) + geometry_.nx * (block.j0 + j)];
}

void Grid::set_cell_kinds(const std::uint8_t *kinds) {
    CompensatedSum change;
    std::int64_t walls = 0, opens = 0;
    for (std::size_t c = 0; c < kinds_.size(); ++c) {
        const std::uint8_t next = kinds ? kinds[c] : static_cast<std::uint8_t>(kSand);
        const double mass = heights_[c] * geometry_.cell_area(static_cast<std::int64_t>(c));
        if (kinds_[c] == kSand && next != kSand) change.add(-mass);
        if (kinds_[c] != kSand && next == kSand) change.add(mass);
        if (kinds_[c] != next) residuals_[c] = 0.0f;
        kinds_[c] = next;
        walls += next == kWall;
        opens += next == kOpen;
    }
    wall_cells_ = walls;
    open_cells_ = opens;
    if (tiled_) tiled_->all_stale = true;  // residuals were reset where kinds changed
    ++masks_version_;
    ledger_.external.add(change.value());
    update_source_summary();
    update_open_levels();
    if (active_) {
        active_->refresh_masks(*this);
        active_->mark_all();
    }
    if (mesh_activity_) mesh_activity_->wake_all();
}

void Grid::restore(GridState &&s) {
    repose_angle_ = s.repose_angle;
    tan_repose_ = std::tan(s.repose_angle);
    mobility_ = s.mobility;
    rest_tolerance_ = s.rest_tolerance;
    max_substeps_ = s.max_substeps;
    threads_ = s.threads;
    scheme_ = s.scheme;
    relaxation_ = s.relaxation;
    side_open_ = s.side_open;
    side_levels_ = std::move(s.side_levels);
    edge_open_ = std::move(s.edge_open);
    edges_open_ = 0;
    for (const std::uint8_t open : edge_open_) edges_open_ += open;
    ++edges_version_;
    update_held_levels();
    set_face_flux_recording(s.record_fluxes);
    heights_ = std::move(s.heights);
    ++heights_version_;
    residuals_ = std::move(s.residuals);
    residual_bounds_ = CellBox{};
    residual_bounds_.add(0, geometry_.nx, 0, geometry_.ny);
    kinds_ = std::move(s.kinds);
    source_ = std::move(s.source);
    clock_.assign(geometry_.tiled() && !source_.empty() ? heights_.size() : 0, 0.0);
    clock_base_ = 0.0;
    bed_ = std::move(s.bed);
    // The tangents and the smallest angle exactly as the setter computes them.
    set_angle_field(s.angle_field.empty() ? nullptr : s.angle_field.data());
    flux_exponent_ = s.flux_exponent;
    static_angle_ = s.static_angle;
    tan_static_ = s.static_angle > 0.0 ? std::tan(s.static_angle) : 0.0;
    moving_ = std::move(s.moving);
    if (tiled_) tiled_->all_stale = true;
    std::int64_t walls = 0, opens = 0;
    for (const std::uint8_t k : kinds_) {
        walls += k == kWall;
        opens += k == kOpen;
    }
    wall_cells_ = walls;
    open_cells_ = opens;
    ledger_ = s.ledger;
    last_step_ = s.last_step;
    update_source_summary();
    update_open_levels();
    // Every tile is looked at again: a sweep over a tile at rest changes
    // nothing, so the results are those of the saved grid.
    if (active_) {
        active_->refresh_masks(*this);
        active_->mark_all();
    }
    if (mesh_activity_) mesh_activity_->wake_all();
}

void Grid::set_source(const double *q) {
    if (q)
        source_.assign(q, q + heights_.size());
    else
        source_.clear();
    if (q && geometry_.tiled() && clock_.size() != heights_.size()) {
        clock_.assign(heights_.size(), 0.0);
        if (tiled_) tiled_->all_stale = true;
    }
    ++masks_version_;
    update_source_summary();
}

void Grid::set_bed(const double *zb) {
    if (zb) {
        bed_.assign(zb, zb + heights_.size());
        lift_to_bed();
    } else {
        bed_.clear();
    }
    ++masks_version_;
    touched_everywhere();
}

void Grid::lift_to_bed() {
    // A bed set before the sand (or above it) lifts the surface to it; the
    // sand this adds comes from the host, as dpsm_set_heights' would.
    CompensatedSum change;
    bool lifted = false;
    for (std::size_t c = 0; c < heights_.size(); ++c) {
        if (!(heights_[c] < bed_[c])) continue;
        if (kinds_[c] == kSand)
            change.add((bed_[c] - heights_[c]) * geometry_.cell_area(static_cast<std::int64_t>(c)));
        heights_[c] = bed_[c];
        residuals_[c] = 0.0f;
        lifted = true;
    }
    if (!lifted) return;
    ++heights_version_;
    ledger_.external.add(change.value());
    if (open_cells_ > 0) update_open_levels();
    if (tiled_) tiled_->all_stale = true;
}

void Grid::set_side_levels(int side, const double *levels) {
    const std::int64_t n = geometry_.is_mesh() ? geometry_.mesh->faces : side < kYMin ? geometry_.ny : geometry_.nx;
    if (levels)
        side_levels_[side].assign(levels, levels + n);
    else
        side_levels_[side].clear();
    update_held_levels();
    ++side_levels_version_;
    touched_everywhere();
}

double Grid::outside_level(std::int64_t i, std::int64_t j) const {
    return level_beyond(side_levels_, geometry_.nx, geometry_.ny, i, j);
}

void Grid::read_face_fluxes(double *fx, double *fy) const {
    const FaceFluxes &fluxes = *fluxes_;
    if (geometry_.dim == 1 || geometry_.is_mesh()) {
        std::copy(fluxes.x.begin(), fluxes.x.end(), fx);
        return;
    }
    // A tile's faces hold the last step's fluxes only if that step visited it.
    const std::int64_t nx = geometry_.nx, ny = geometry_.ny;
    for (std::int64_t t = 0; t < active_->tiles(); ++t) {
        const CellBox tile = active_->tile_cells(t);
        const bool current = fluxes.tile_step[static_cast<std::size_t>(t)] == fluxes.step;
        const std::int64_t x1 = tile.i1 + (tile.i1 == nx ? 1 : 0), y1 = tile.j1 + (tile.j1 == ny ? 1 : 0);
        for (std::int64_t j = tile.j0; j < tile.j1; ++j) {
            const std::size_t at = static_cast<std::size_t>(tile.i0 + (nx + 1) * j);
            if (current)
                std::copy_n(fluxes.x.begin() + at, x1 - tile.i0, fx + at);
            else
                std::fill_n(fx + at, x1 - tile.i0, 0.0);
        }
        for (std::int64_t j = tile.j0; j < y1; ++j) {
            const std::size_t at = static_cast<std::size_t>(tile.i0 + nx * j);
            if (current)
                std::copy_n(fluxes.y.begin() + at, tile.i1 - tile.i0, fy + at);
            else
                std::fill_n(fy + at, tile.i1 - tile.i0, 0.0);
        }
    }
}

SideLevelRange side_level_range(const std::array<bool, 4> &open, const std::array<std::vector<double>, 4> &levels) {
    SideLevelRange range{std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
    auto take = [&](double level) {
        range.lowest = std::min(range.lowest, level);
        range.highest = std::max(range.highest, level);
    };
    for (int side = 0; side < 4; ++side) {
        if (!open[side]) continue;
        if (levels[side].empty()) take(0.0);  // a side without levels holds 0
        for (const double level : levels[side]) take(level);
    }
    if (range.lowest > range.highest) range = SideLevelRange{};  // no side open
    return range;
}

void Grid::set_edge_open(const std::uint8_t *open) {
    const Mesh &mesh = *geometry_.mesh;
    edges_open_ = 0;
    if (open) {
        edge_open_.assign(open, open + mesh.faces);
        for (std::int64_t f = 0; f < mesh.faces; ++f) {
            edge_open_[f] = mesh.face_b[f] < 0 && edge_open_[f] != 0;
            edges_open_ += edge_open_[f];
        }
    } else {
        edge_open_.clear();
    }
    side_open_[0] = false;  // the faces say which edges are open
    ++edges_version_;
    update_held_levels();
    touched_everywhere();
}

void Grid::update_held_levels() {
    if (geometry_.is_mesh()) {
        // The levels beyond the open faces of the domain edge.
        const Mesh &mesh = *geometry_.mesh;
        const std::vector<double> &levels = side_levels_[0];
        bool any = false;
        double lo = 0.0, hi = 0.0;
        for (std::int64_t f = 0; f < mesh.live_faces; ++f) {
            if (mesh.face_b[f] >= 0 || !edge_open(f)) continue;
            const double level = levels.empty() ? 0.0 : levels[f];
            lo = any ? std::min(lo, level) : level;
            hi = any ? std::max(hi, level) : level;
            any = true;
        }
        side_level_min_ = lo;
        side_level_max_ = hi;
        return;
    }
    const SideLevelRange range = side_level_range(side_open_, side_levels_);
    side_level_min_ = range.lowest;
    side_level_max_ = range.highest;
}

void Grid::set_face_flux_recording(bool on) {
    record_fluxes_ = on;
    if (!on) {
        fluxes_.reset();
        return;
    }
    if (fluxes_) return;
    auto fluxes = std::make_unique<FaceFluxes>();
    const std::size_t nx = static_cast<std::size_t>(geometry_.nx), ny = static_cast<std::size_t>(geometry_.ny);
    if (geometry_.is_mesh()) {
        fluxes->x.assign(static_cast<std::size_t>(geometry_.mesh->faces), 0.0);
        fluxes_ = std::move(fluxes);
        return;
    }
    fluxes->x.assign((nx + 1) * ny, 0.0);
    if (geometry_.dim == 2) {
        fluxes->y.assign(nx * (ny + 1), 0.0);
        fluxes->tile_step.assign(static_cast<std::size_t>(active_->tiles()), 0);
    }
    fluxes_ = std::move(fluxes);
}

void Grid::set_angle_field(const double *theta) {
    if (theta) {
        angle_field_.assign(theta, theta + heights_.size());
        tan_field_.resize(angle_field_.size());
        double lowest = angle_field_[0];
        for (std::size_t c = 0; c < angle_field_.size(); ++c) {
            tan_field_[c] = std::tan(angle_field_[c]);
            lowest = angle_field_[c] < lowest ? angle_field_[c] : lowest;
        }
        min_angle_field_ = lowest;
    } else {
        angle_field_.clear();
        tan_field_.clear();
    }
    ++masks_version_;
    touched_everywhere();
}

void Grid::set_static_angle(double theta) {
    static_angle_ = theta;
    tan_static_ = std::tan(theta);
    // Every cell starts at rest: sand moves first where the static angle is exceeded.
    moving_.assign(heights_.size(), 0);
    if (tiled_) tiled_->all_stale = true;
    touched_everywhere();
}

void Grid::update_open_levels() {
    double lo = 0.0, hi = 0.0;
    bool first = true;
    for (std::size_t c = 0; c < kinds_.size(); ++c) {
        if (kinds_[c] != kOpen) continue;
        lo = first || heights_[c] < lo ? heights_[c] : lo;
        hi = first || heights_[c] > hi ? heights_[c] : hi;
        first = false;
    }
    open_level_min_ = lo;
    open_level_max_ = hi;
}

void Grid::update_source_summary() {
    bool nonzero = false;
    for (std::size_t c = 0; c < source_.size() && !nonzero; ++c)
        nonzero = kinds_[c] == kSand && source_[c] != 0.0;
    source_rate_nonzero_ = nonzero;
    source_mass_rate_ = nonzero ? sand_mass(source_.data()) : 0.0;
    if (active_) active_->refresh_source(*this);
}

}  // namespace dpsm
