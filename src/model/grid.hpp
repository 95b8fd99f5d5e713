// The state of one granular surface: geometry, parameters, masks, source,
// heights and the mass ledger. Grid keeps the ledger consistent with every
// change the host makes; the arguments reach it already checked by api/capi.cpp.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "model/changes.hpp"
#include "model/face_fluxes.hpp"
#include "model/ledger.hpp"
#include "model/mesh.hpp"
#include "model/side_levels.hpp"
#include "model/threads.hpp"

namespace dpsm {

enum Side { kXMin = 0, kXMax = 1, kYMin = 2, kYMax = 3 };
// kOutside never lies on a grid: a sweep gives it to the cells beyond an
// open side, which hold the side's level as open cells hold theirs, so that
// what leaves through each side is told from what leaves through open cells.
enum CellKind : std::uint8_t { kSand = 0, kWall = 1, kOpen = 2, kOutside = 3 };

// The lowest and highest level held beyond the open sides: each open side's
// levels, 0 for an open side without levels; (0, 0) when no side is open.
struct SideLevelRange {
    double lowest = 0.0, highest = 0.0;
};
SideLevelRange side_level_range(const std::array<bool, 4> &open, const std::array<std::vector<double>, 4> &levels);

enum Scheme { kPairwise = 0, kIsotropic = 1 };
// How dpsm_step moves the surface (the values of DPSM_RELAX_*).
enum Relaxation { kTimeAccurate = 0, kToRest = 1, kAutoRelaxation = 2, kLocalSteps = 3 };

struct Geometry {
    int dim;             // 1 or 2
    bool axisymmetric;   // a 1D grid in radius r: cell i spans [i dx, (i+1) dx]
    std::int64_t nx, ny; // ny == 1 in 1D and on a mesh
    double dx, dy;       // dy == 1 in 1D, so that a cell's area is dx; on a mesh the smallest face distance
    // An unstructured mesh (dim == 2, nx its cells, ny == 1); null on grids.
    std::shared_ptr<const Mesh> mesh;

    std::int64_t cells() const { return nx * ny; }
    bool is_mesh() const { return mesh != nullptr; }
    // A 2D Cartesian grid: the tiled engine's.
    bool tiled() const { return dim == 2 && !mesh; }
    // The area (1D: length; axisymmetric: the ring's area 2 pi r dr) that
    // turns a cell's height into its mass.
    // A ghost of a distributed mesh weighs nothing here: its owner counts it.
    double cell_area(std::int64_t c) const {
        if (mesh) return c < mesh->owned ? mesh->area[static_cast<std::size_t>(c)] : 0.0;
        return axisymmetric ? kTwoPi * (static_cast<double>(c) + 0.5) * dx * dx : dx * dy;
    }
    // The length (axisymmetric: circumference) of the x face on the high side
    // of cell i; the face at the axis has length 0.
    double x_face_length(std::int64_t i) const {
        return axisymmetric ? kTwoPi * static_cast<double>(i + 1) * dx : dy;
    }
    static constexpr double kTwoPi = 6.283185307179586476925;
};

// What an engine keeps of its own on a grid (model/engine.hpp: its active
// set, scratch and clocks), hearing of every change the host makes.
struct EngineState : ChangeListener {};

class Distribution;

// What the last step did, for dpsm_get_step_info.
struct StepInfo {
    std::int64_t substeps = 0;
    std::int64_t substeps_evaluated = 0;  // less than substeps where local time steps passed ticks over
    double time_integrated = 0.0;
    bool at_rest = false;
    double max_excess_slope = 0.0;
    double cell_updates = 0.0;
    // On a distributed grid, this rank's own: its cell updates, and the
    // messages and bytes of ghost cells' values it sent (0 on a serial grid).
    double rank_cell_updates = 0.0, messages_sent = 0.0, bytes_sent = 0.0;
    // Sub-steps between two exchanges of ghost values (0 on a serial grid).
    double substeps_per_exchange = 0.0;
};

// Everything of a grid besides its geometry that later results depend on, as
// a restart file holds it (io/restart.cpp); what Grid derives from these fields
// (tangents, counts, summaries, the active set) is not in it.
struct GridState {
    double repose_angle = 0.0, mobility = 0.0, rest_tolerance = 0.0;
    std::int64_t max_substeps = 0;
    int threads = 0;
    Scheme scheme = kPairwise;
    std::array<bool, 4> side_open{};
    SideLevels side_levels;
    bool record_fluxes = false;
    std::vector<double> heights;
    std::vector<float> residuals;
    std::vector<std::uint8_t> kinds;
    std::vector<std::uint8_t> edge_open;           // a mesh's open edge faces; empty: as side_open[0]
    std::vector<double> source, bed, angle_field;  // empty: none
    double flux_exponent = 1.0;
    double static_angle = 0.0;          // 0: no hysteresis
    std::vector<std::uint8_t> moving;   // empty unless static_angle > 0
    Relaxation relaxation = kTimeAccurate;  // what a restart file without a word of it meant
    MassLedger ledger;
    StepInfo last_step;
};

class Grid;
// Sand thinner than this above the bed is left in place: the height scale of
// the rest tolerance, tol tan(theta) d. Without it a drained slope would thin
// geometrically (a face takes a share of what is there) and never rest.
double bed_film(const Grid &grid);

class Grid {
public:
    explicit Grid(const Geometry &geometry);
    ~Grid();
    Grid(const Grid &) = delete;
    Grid &operator=(const Grid &) = delete;

    const Geometry &geometry() const { return geometry_; }

    // Parameters.
    double repose_angle() const { return repose_angle_; }
    double tan_repose() const { return tan_repose_; }
    void set_repose_angle(double theta);
    double mobility() const { return mobility_; }
    void set_mobility(double nu) { mobility_ = nu; }
    double rest_tolerance() const { return rest_tolerance_; }
    void set_rest_tolerance(double tol) {
        rest_tolerance_ = tol;
        notify(kLawChanged);
    }
    std::int64_t max_substeps() const { return max_substeps_; }
    void set_max_substeps(std::int64_t n) { max_substeps_ = n; }
    int threads() const { return threads_; }  // 0: OpenMP's default
    // The threads a step runs on (model/threads.hpp).
    int step_threads() const { return thread_count(threads_, distribution_ != nullptr); }
    void set_threads(int n) { threads_ = n; }
    // Where the host counts cells and array positions from in messages on a
    // grid: 0 as C writes them, 1 as Fortran does (a mesh has its own start
    // index, model/mesh.hpp). It changes no result.
    int index_base() const { return index_base_; }
    void set_index_base(int base) { index_base_ = base; }
    Scheme scheme() const { return scheme_; }
    void set_scheme(Scheme scheme) {
        scheme_ = scheme;
        notify(kLawChanged);
    }
    // The physics of real scenes (dpsm_set_bedrock and friends); each is empty
    // or at its default when a scene does not use it, and a scene that uses
    // none of them is stepped by the vectorised kernels.
    const std::vector<double> &bed() const { return bed_; }  // empty: none
    // NULL: none. A bed above a cell lifts the cell to it (booked as external mass).
    void set_bed(const double *zb);
    const std::vector<double> &angle_field() const { return angle_field_; }  // radians; empty: uniform
    const std::vector<double> &tan_field() const { return tan_field_; }      // tan of angle_field
    void set_angle_field(const double *theta);                               // NULL: uniform
    // The smallest angle of repose of any cell: it sets the stable sub-step.
    double min_repose_angle() const {
        return distributed_min_angle_ > 0.0 ? distributed_min_angle_ : own_min_repose_angle();
    }
    // The same over this grid's own cells alone (on a block: the block's).
    double own_min_repose_angle() const { return angle_field_.empty() ? repose_angle_ : min_angle_field_; }
    // On a block of a distributed grid: the smallest angle over all blocks,
    // set by the Distribution before each step.
    void set_distributed_min_repose_angle(double theta) { distributed_min_angle_ = theta; }
    double flux_exponent() const { return flux_exponent_; }
    void set_flux_exponent(double p) {
        flux_exponent_ = p;
        notify(kLawChanged);
    }
    // Hysteresis: on once a static angle is set; moving() then holds, per
    // cell, whether one of its faces carried sand in the last sub-step.
    bool hysteresis() const { return static_angle_ > 0.0; }
    double static_angle() const { return static_angle_; }
    double tan_static() const { return tan_static_; }
    void set_static_angle(double theta);
    const std::vector<std::uint8_t> &moving() const { return moving_; }
    std::vector<std::uint8_t> &moving_for_stepping() { return moving_; }
    bool uses_physics() const {
        return !bed_.empty() || !tan_field_.empty() || flux_exponent_ != 1.0 || hysteresis();
    }

    // How dpsm_step moves the surface: time-accurate sub-steps, the fast
    // relaxation to rest (structured/relax_to_rest.hpp), or the second where it applies.
    Relaxation relaxation() const { return relaxation_; }
    void set_relaxation(Relaxation relaxation) { relaxation_ = relaxation; }

    bool side_open(int side) const { return side_open_[side]; }
    bool any_side_open() const {
        return side_open_[0] || side_open_[1] || side_open_[2] || side_open_[3] || edges_open_ > 0;
    }
    // On a mesh, side 0 stands for its domain edge (DPSM_MESH_EDGE); a host
    // may open some of its faces and not others: per face, in the library's
    // order (empty: every edge face as side_open(0) says).
    const std::vector<std::uint8_t> &edge_open_flags() const { return edge_open_; }
    bool edge_open(std::int64_t face) const {
        return edge_open_.empty() ? side_open_[0] : edge_open_[static_cast<std::size_t>(face)] != 0;
    }
    void set_edge_open(const std::uint8_t *open);  // per face of the mesh, library order; NULL: as side_open(0)
    void set_side_open(int side, bool open) {
        side_open_[side] = open;
        if (geometry_.is_mesh()) {
            edge_open_.clear();
            edges_open_ = 0;
        }
        update_held_levels();
        notify(kSidesChanged | kLawChanged);
    }
    // The surface level outside an open side, per boundary face (k counts
    // along the side: j for the x sides, i for the y sides); 0 unless the
    // host set levels (dpsm_set_side_levels).
    double side_level(int side, std::int64_t k) const { return side_level_of(side_levels_, side, k); }
    const std::vector<double> &side_levels(int side) const { return side_levels_[side]; }  // empty: all 0
    void set_side_levels(int side, const double *levels);                                     // NULL: all 0
    // The level of the cell (i, j) beyond the domain that a sweep reads as
    // the outside of the sides (model/side_levels.hpp).
    double outside_level(std::int64_t i, std::int64_t j) const;
    // The lowest and highest level held beyond the open sides (0 and 0 when
    // no side is open or none has levels).
    double side_level_min() const { return side_level_min_; }
    double side_level_max() const { return side_level_max_; }

    // Cell data, x fastest.
    const std::vector<double> &heights() const { return heights_; }
    std::vector<double> &heights_for_stepping() { return heights_; }
    // What each cell's last updates lost to rounding, carried into its next
    // update (a per-cell TwoSum), so that a surface at steady state under a
    // source does not leak mass one half-ulp at a time.
    const std::vector<float> &residuals() const { return residuals_; }
    std::vector<float> &residuals_for_stepping() { return residuals_; }
    void swap_heights(std::vector<double> &heights, std::vector<float> &residuals) {
        heights_.swap(heights);
        residuals_.swap(residuals);
    }
    const std::vector<std::uint8_t> &kinds() const { return kinds_; }
    const std::vector<double> &source() const { return source_; }  // empty: none
    bool has_obstacles() const { return wall_cells_ > 0 || open_cells_ > 0; }
    bool has_open_cells() const { return open_cells_ > 0; }
    // The lowest and highest level held by open cells (kept up to date by the
    // host's calls, the only ones that change them).
    double open_level_min() const { return open_level_min_; }
    double open_level_max() const { return open_level_max_; }
    bool source_active() const { return source_rate_nonzero_; }
    double source_mass_rate() const { return source_mass_rate_; }

    // A block of cells [i0, i0+ni) x [j0, j0+nj), values x fastest: sets the
    // heights (add = false) or adds to them (add = true), booking the change
    // on sand cells as external mass.
    struct Block {
        std::int64_t i0, j0, ni, nj;
    };
    Block whole() const { return {0, 0, geometry_.nx, geometry_.ny}; }
    void write_heights(const Block &block, const double *values, bool add);
    void read_heights(const Block &block, double *values) const;
    void set_cell_kinds(const std::uint8_t *kinds);   // NULL: all sand; books mass that comes or goes
    // Takes every field of a checked state read from a restart file, on a
    // new grid of the same geometry. Unlike the setters it books nothing in
    // the ledger (the state carries its ledger); it recomputes what is derived.
    void restore(GridState &&state);
    void set_source(const double *q);                 // NULL: none

    // The volume each face carried in the last step, recorded only when the
    // host asked for it (dpsm_set_face_flux_recording). x faces: (nx + 1) * ny,
    // face i on the low side of cell i; y faces: nx * (ny + 1) (2D only).
    bool records_face_fluxes() const { return record_fluxes_; }
    void set_face_flux_recording(bool on);
    FaceFluxes &face_fluxes() { return *fluxes_; }
    const FaceFluxes &face_fluxes() const { return *fluxes_; }
    const FaceFluxes *face_fluxes_if_any() const { return fluxes_.get(); }

    // Mass on sand cells now, a compensated sum.
    double total_mass() const;
    // Mass of values (heights or source rates) on sand cells: sum v * area.
    double sand_mass(const double *values) const;
    MassLedger &ledger() { return ledger_; }
    const MassLedger &ledger() const { return ledger_; }

    // What the engine that steps this grid keeps of its own (model/engine.hpp);
    // null until the grid's handle attaches it.
    EngineState *engine_state() const { return engine_state_.get(); }
    void set_engine_state(std::unique_ptr<EngineState> state) { engine_state_ = std::move(state); }

    StepInfo &last_step() { return last_step_; }
    const StepInfo &last_step() const { return last_step_; }

    // The grid's part in a distributed grid (model/distribution.hpp); null on
    // a serial grid, which never pays for any of it.
    Distribution *distribution() const { return distribution_.get(); }
    void set_distribution(std::unique_ptr<Distribution> distribution);
    // The sum over all ranks of a distributed grid; `local` on a serial grid.
    double global_sum(double local) const;

    // Tells the engine's state and the distribution what changed
    // (model/changes.hpp); `cells` with kCellsChanged.
    void notify(unsigned what, const ChangedCells *cells = nullptr) const;

private:
    void update_source_summary();
    void update_open_levels();
    void update_held_levels();
    void lift_to_bed();
    void count_kinds();

    Geometry geometry_;
    double repose_angle_;
    double tan_repose_;
    double mobility_;
    double rest_tolerance_;
    std::int64_t max_substeps_;
    std::array<bool, 4> side_open_{};
    SideLevels side_levels_;
    double side_level_min_ = 0.0, side_level_max_ = 0.0;

    std::vector<double> heights_;
    std::vector<float> residuals_;
    std::vector<std::uint8_t> kinds_;
    std::vector<double> source_;
    std::vector<double> bed_;
    std::vector<double> angle_field_, tan_field_;
    double min_angle_field_ = 0.0;
    double distributed_min_angle_ = 0.0;  // 0: not distributed
    double flux_exponent_ = 1.0;
    double static_angle_ = 0.0, tan_static_ = 0.0;  // 0: no hysteresis
    std::vector<std::uint8_t> moving_;
    std::unique_ptr<EngineState> engine_state_;
    std::vector<std::uint8_t> edge_open_;
    std::int64_t edges_open_ = 0;  // faces of edge_open_ that are open
    bool record_fluxes_ = false;
    std::unique_ptr<FaceFluxes> fluxes_;
    Scheme scheme_;
    Relaxation relaxation_ = kAutoRelaxation;
    int threads_ = 0;
    int index_base_ = 0;
    std::int64_t wall_cells_ = 0;
    std::int64_t open_cells_ = 0;
    double open_level_min_ = 0.0, open_level_max_ = 0.0;
    bool source_rate_nonzero_ = false;
    double source_mass_rate_ = 0.0;

    MassLedger ledger_;
    StepInfo last_step_;
    std::unique_ptr<Distribution> distribution_;
    mutable std::vector<std::int64_t> changed_cells_;  // write_heights' list for listeners that want one
};

}  // namespace dpsm
