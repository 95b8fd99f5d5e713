// What the mesh engine keeps of its own on a grid between calls
// (model/engine.hpp): the cells the next sub-step must look at, the passes'
// scratch, and on a part of a distributed mesh its exchange with the ranks
// around it. It hears of every change the host makes (model/changes.hpp).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "mesh/index_set.hpp"
#include "mesh/list_passes.hpp"
#include "mesh/ghost_exchange.hpp"
#include "mesh/step_classes.hpp"
#include "model/engine.hpp"
#include "model/grid.hpp"
#include "model/switches.hpp"

namespace dpsm {

// Which cells the next sub-step must look at, kept between steps: a face
// can start to carry sand only where a cell within one face of its cells
// changed (its slope reads its cells' least-squares gradients).
struct MeshActivity {
    std::vector<std::uint8_t> hot;      // per cell; meaningless while all_hot
    std::vector<std::int64_t> hot_list;  // the cells with hot == 1
    bool all_hot = true;

    // While all_hot, every hot flag is 0.
    void wake_all() {
        for (const std::int64_t c : hot_list) hot[c] = 0;
        hot_list.clear();
        all_hot = true;
    }
    // Starts a list of hot cells from none.
    void cool_all(int threads = 1) {
        for_each_item(hot_list, threads, [&](std::int64_t c) { hot[c] = 0; });
        hot_list.clear();
        all_hot = false;
    }
    void wake(std::int64_t c) {
        if (all_hot || hot[c]) return;
        hot[c] = 1;
        hot_list.push_back(c);
    }
    // A cell that changed and the cells whose gradients read it: a face
    // reads its cells' heights and gradients.
    template <class Visit>
    static void for_each_around(const Mesh &mesh, std::int64_t c, const Visit &visit) {
        visit(c);
        for (std::int64_t k = mesh.grad_start[c]; k < mesh.grad_start[c + 1]; ++k) visit(mesh.grad_cells[k]);
    }
    void wake_around(const Mesh &mesh, std::int64_t c) {
        if (all_hot) return;
        for_each_around(mesh, c, [&](std::int64_t e) { wake(e); });
    }
    // After cool_all: the cells of a set hot, listed in cell order (the set empties).
    void wake_set(IndexSet &woken, int threads) {
        woken.take(hot_list, threads);
        for_each_item(hot_list, threads, [&](std::int64_t c) { hot[c] = 1; });
    }
    bool may_move() const { return all_hot || !hot_list.empty(); }
};

struct MeshState final : EngineState {
    explicit MeshState(const Grid &grid);

    void changed(const Grid &grid, unsigned what, const ChangedCells *cells) override;
    bool wants_changed_cells() const override { return true; }

    MeshActivity activity;
    // The switches of tests (model/switches.hpp), read at the start of each step's work.
    Switches switches;
    // On a part of a distributed mesh: its exchange with the ranks around it
    // (the grid's Distribution), found at the start of each step.
    GhostExchange *exchange = nullptr;

    // The passes' scratch (mesh/mesh_engine.cpp). Per face, as volumes per
    // unit time from a to b: the monotone flux, the gradient flow's, the
    // limited one; the pull V g t; the slope beyond tan(theta). Per cell: M^-1 P, the limiter's factors
    // for what enters and what leaves. Outside a sub-step's faces and cells
    // each holds 0 (the limiters 1).
    std::vector<double> gx, gy;   // least-squares gradients
    std::vector<double> flux;     // the limited flux
    std::vector<double> low, high, pull, excess;
    std::vector<double> pull_x, pull_y;
    std::vector<double> limit_in, limit_out;
    // Per face, whether its slope exceeds its threshold; the steep faces (a
    // list that may hold faces no longer steep, dropped as it is read).
    std::vector<std::uint8_t> steep;
    std::vector<std::int64_t> steep_faces;
    bool steep_faces_listed = true;  // false: a dense sub-step left them to `steep` alone
    std::vector<std::uint8_t> became_steep;  // per face looked at, in the sub-step's list: it turned steep
    std::vector<std::int64_t> pull_cells, limit_cells;
    std::vector<std::int64_t> pulling_ghosts;  // a part's ghosts whose pulls are not 0
    std::vector<std::uint32_t> face_seen, cell_seen;
    IndexSet cell_set, face_set;  // the sparse passes' lists, built in index order
    std::uint32_t stamp = 0;
    std::vector<std::int64_t> faces, gradient_cells, update_cells;
    std::vector<std::int64_t> changed_ghosts;  // a part's ghosts whose owners sent new values
    // A part's exchanges in every sub-step, kept so that they allocate nothing
    // once warm: the fields sent, the sub-step's summary the ranks agree on.
    std::vector<GhostField> ghost_fields;
    std::vector<SubstepSummary> agreed;
    std::vector<double> available;         // bed: the sand (a volume) a cell's faces may take
    std::vector<std::uint8_t> carried;     // dense: per cell, a face of it carried sand
    bool flux_clean = true;
    // A part that takes several sub-steps per exchange: the owned cells
    // updated since the last exchange (all of them when batch_all).
    std::vector<std::int64_t> batch_cells;
    std::vector<std::uint8_t> in_batch;
    bool batch_all = false;

    // Lazy sources (mesh/mesh_engine.cpp, "Sources in closed form"), in a
    // step that applies them: per cell, the sub-step of the step after which
    // its stored height is current (0 at the start of every step; a ghost
    // takes its owner's with its height); the cells a sub-step keeps hot
    // because a source may make their faces steep, each flagged in `watch`
    // (kWatched), and the cells whose moves put them there (kNearMoves).
    bool lazy = false;
    double lazy_substeps = 0.0;  // the step's sub-steps, over which the sources act
    std::vector<double> since;
    // A dense sub-step's heights as its passes read them, found once (the
    // same bits as reading them through the clocks); and a look under the
    // sources' at its two times.
    std::vector<double> heights_read, heights_read_earlier;
    std::vector<std::uint8_t> watch;
    std::vector<std::int64_t> watched_cells, moved_cells;
    // A sub-step moved sand since the last look at whether a source may
    // still make a face steep before the step ends; that look's answer.
    bool moved_since_look = false, source_may_steepen = false;
    // Scratch of that look: per cell, gradients at two times; per face, steep
    // at either (look_steep), and at the first (look_steep_earlier).
    std::vector<double> look_gx, look_gy, look_gx_later, look_gy_later;
    std::vector<std::uint8_t> look_steep, look_steep_earlier;

    // What the host's masks, sources and edges make of the mesh, found again
    // after the host changed them (lists_current false).
    std::vector<std::int64_t> source_cells;        // owned sand cells with a source
    // The sources of sand cells (0 elsewhere), as a lazy source's lag reads them.
    std::vector<double> sand_source;
    // Per cell, whether a source moves its height or its gradient's stencil
    // (kSourceReach), and whether it or a cell across a face does
    // (kSourceNear: its faces' slopes move under the sources alone).
    std::vector<std::uint8_t> source_reach;
    // The faces whose slopes move under the sources alone, and their cells.
    std::vector<std::int64_t> source_faces, source_face_cells;
    std::vector<std::int64_t> ghost_source_cells;  // a part's ghosts with a source, stepped where they are in reach
    std::vector<std::int64_t> sink_faces;          // faces onto open edges or open cells
    std::vector<std::uint8_t> carrying;            // per face: what it does (FaceRole in mesh_engine.cpp)
    std::vector<std::uint8_t> beside_wall;         // per cell: a face of it lies along a wall; empty: none does
    // The faces the dense face pass leaves to FaceLaw::terms when it runs in
    // lanes (mesh/face_lanes.hpp): on the domain edge, along a wall or
    // carrying nothing, in face order.
    std::vector<std::int64_t> faces_off_lanes;
    bool lists_current = false;

    // Local time steps (DPSM_RELAX_LOCAL_STEPS, mesh/step_classes.hpp): the
    // classes, found at the first step that takes them.
    std::unique_ptr<const StepClasses> classes;
    // In a step, the hot cells (the activity's hot_list moves here) by the
    // finest class of their faces: a tick reads the levels it fires.
    std::vector<std::vector<std::int64_t>> hot_by_level;
    // And the steep faces (steep_faces moves here) by their classes.
    std::vector<std::vector<std::int64_t>> steep_by_level;
    // While every cell is hot: the tick by which every cell a change woke
    // has seen all its faces fire since (the same tick at which those cells
    // would cool on the lists), so that sand at rest is found at the same
    // tick whichever way a tick runs.
    std::int64_t pending_until = 0;
    // With a static angle, per owned cell: a face of it carried sand since
    // all its faces last fired together (mesh_engine.cpp, note_moving_cells).
    std::vector<std::uint8_t> carried_in_cycle;
};

MeshState &mesh_state(Grid &grid);
const MeshState &mesh_state(const Grid &grid);

}  // namespace dpsm
