#include "model/grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "dpsm/dpsm.h"
#include "model/distribution.hpp"

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
      scheme_(geometry.dim == 2 ? kIsotropic : kPairwise) {}

Grid::~Grid() = default;

void Grid::set_distribution(std::unique_ptr<Distribution> distribution) { distribution_ = std::move(distribution); }

double Grid::global_sum(double local) const { return distribution_ ? distribution_->sum(local) : local; }

void Grid::notify(unsigned what, const ChangedCells *cells) const {
    if (engine_state_) engine_state_->changed(*this, what, cells);
    if (distribution_) distribution_->changed(*this, what, cells);
}

void Grid::set_repose_angle(double theta) {
    repose_angle_ = theta;
    tan_repose_ = std::tan(theta);
    notify(kLawChanged);
}

double Grid::sand_mass(const double *values) const {
    CompensatedSum sum;
    for (std::size_t c = 0; c < kinds_.size(); ++c)
        if (kinds_[c] == kSand) sum.add(values[c] * geometry_.cell_area(static_cast<std::int64_t>(c)));
    return sum.value();
}

double Grid::total_mass() const { return sand_mass(heights_.data()); }

void Grid::write_heights(const Block &block, const double *values, bool add) {
    // Listeners that step cells one by one (a mesh) hear which cells changed.
    const bool list = (engine_state_ && engine_state_->wants_changed_cells()) ||
                      (distribution_ && distribution_->wants_changed_cells());
    changed_cells_.clear();
    // Book the difference cell by cell so that a host that changes a few cells
    // of a large pile gets the change exactly, not a difference of two large sums.
    CompensatedSum change;
    for (std::int64_t j = 0; j < block.nj; ++j)
        for (std::int64_t i = 0; i < block.ni; ++i) {
            const std::int64_t c = (block.i0 + i) + geometry_.nx * (block.j0 + j);
            const double v = values[i + block.ni * j];
            const double next = add ? heights_[c] + v : v;
            if (kinds_[c] == kSand) change.add((next - heights_[c]) * geometry_.cell_area(c));
            if (list && (next != heights_[c] || residuals_[c] != 0.0f)) changed_cells_.push_back(c);
            heights_[c] = next;
            residuals_[c] = 0.0f;
        }
    ledger_.external.add(change.value());
    if (open_cells_ > 0) update_open_levels();
    const ChangedCells cells{block.i0, block.j0, block.ni, block.nj, list ? &changed_cells_ : nullptr};
    notify(kCellsChanged, &cells);
}

void Grid::read_heights(const Block &block, double *values) const {
    for (std::int64_t j = 0; j < block.nj; ++j)
        for (std::int64_t i = 0; i < block.ni; ++i)
            values[i + block.ni * j] = heights_[(block.i0 + i) + geometry_.nx * (block.j0 + j)];
}

void Grid::set_cell_kinds(const std::uint8_t *kinds) {
    CompensatedSum change;
    for (std::size_t c = 0; c < kinds_.size(); ++c) {
        const std::uint8_t next = kinds ? kinds[c] : static_cast<std::uint8_t>(kSand);
        const double mass = heights_[c] * geometry_.cell_area(static_cast<std::int64_t>(c));
        if (kinds_[c] == kSand && next != kSand) change.add(-mass);
        if (kinds_[c] != kSand && next == kSand) change.add(mass);
        if (kinds_[c] != next) residuals_[c] = 0.0f;
        kinds_[c] = next;
    }
    count_kinds();
    ledger_.external.add(change.value());
    update_source_summary();
    update_open_levels();
    notify(kMasksChanged);  // residuals were reset where kinds changed, too
}

void Grid::count_kinds() {
    std::int64_t walls = 0, opens = 0;
    for (const std::uint8_t k : kinds_) {
        walls += k == kWall;
        opens += k == kOpen;
    }
    wall_cells_ = walls;
    open_cells_ = opens;
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
    update_held_levels();
    set_face_flux_recording(s.record_fluxes);
    heights_ = std::move(s.heights);
    residuals_ = std::move(s.residuals);
    kinds_ = std::move(s.kinds);
    source_ = std::move(s.source);
    bed_ = std::move(s.bed);
    // The tangents and the smallest angle exactly as the setter computes them.
    set_angle_field(s.angle_field.empty() ? nullptr : s.angle_field.data());
    flux_exponent_ = s.flux_exponent;
    static_angle_ = s.static_angle;
    tan_static_ = s.static_angle > 0.0 ? std::tan(s.static_angle) : 0.0;
    moving_ = std::move(s.moving);
    count_kinds();
    ledger_ = s.ledger;
    last_step_ = s.last_step;
    update_source_summary();
    update_open_levels();
    // Every cell is looked at again: a sub-step over cells at rest changes
    // nothing, so the results are those of the saved grid.
    const ChangedCells cells{0, 0, geometry_.nx, geometry_.ny, nullptr};
    notify(kEverythingChanged, &cells);
}

void Grid::set_source(const double *q) {
    if (q)
        source_.assign(q, q + heights_.size());
    else
        source_.clear();
    update_source_summary();
    notify(kSourcesChanged);
}

void Grid::set_bed(const double *zb) {
    if (zb) {
        bed_.assign(zb, zb + heights_.size());
        lift_to_bed();
    } else {
        bed_.clear();
    }
    notify(kMasksChanged | kLawChanged);
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
    ledger_.external.add(change.value());
    if (open_cells_ > 0) update_open_levels();
    const ChangedCells cells{0, 0, geometry_.nx, geometry_.ny, nullptr};
    notify(kCellsChanged, &cells);
}

void Grid::set_side_levels(int side, const double *levels) {
    const std::int64_t n = geometry_.is_mesh() ? geometry_.mesh->faces : side < kYMin ? geometry_.ny : geometry_.nx;
    if (levels)
        side_levels_[side].assign(levels, levels + n);
    else
        side_levels_[side].clear();
    update_held_levels();
    notify(kSidesChanged | kLawChanged);
}

double Grid::outside_level(std::int64_t i, std::int64_t j) const {
    return level_beyond(side_levels_, geometry_.nx, geometry_.ny, i, j);
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
    update_held_levels();
    notify(kSidesChanged | kLawChanged);
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
    if (geometry_.dim == 2) fluxes->y.assign(nx * (ny + 1), 0.0);  // the engine numbers their tiles
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
    notify(kMasksChanged | kLawChanged);
}

void Grid::set_static_angle(double theta) {
    static_angle_ = theta;
    tan_static_ = std::tan(theta);
    // Every cell starts at rest: sand moves first where the static angle is exceeded.
    moving_.assign(heights_.size(), 0);
    notify(kLawChanged);
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
}

}  // namespace dpsm
