// Local time steps on a mesh (DPSM_RELAX_LOCAL_STEPS): each cell steps at
// the pace of its own stable bound, in power-of-two classes.
//
// A cell's bound is area / (sum of its faces' conductances), the per-cell
// form of Mesh::step_scale; its class k is the largest with 2^k step_scale
// within it (at most kMaxStepClass). A step of N ticks of the smallest
// class's sub-step fires, at tick j, every face whose class (the smaller of
// its cells') divides into j: k <= the trailing zeros of j, every class at
// tick 0. A face that fires carries the amounts of its class's span,
// min(2^k, N - j) ticks, and both its cells take them at once, so mass is
// exact face by face (Osher and Sanders' local steps with the flux applied
// where it is computed); a cell's firing faces are of its own class or
// finer, so their spans stay within its own bound and each tick is a convex
// update, limited like any sub-step.
//
// Which items a tick reads is fixed by the geometry: the faces that fire,
// the cells whose gradients and pulls they read, the faces that carry
// those cells' pulls and the cells that limit and take those faces'
// fluxes. Each list below is sorted by the finest tick level at which an
// item takes part (then by index), so that the items of a tick at level L
// are a prefix: list[0 .. end[L]).
//
// On a part of a distributed mesh the lists hold the owned cells and the
// faces that touch them; a ghost's levels are its owner's, and the top
// class is the largest on any rank, so that every rank ticks alike and each
// item fires at the tick it fires at on the whole mesh.
#pragma once

#include <cstdint>
#include <vector>

#include "model/mesh.hpp"

namespace dpsm {

class GhostExchange;
class Collectives;

// Spans of up to 2^20 ticks: a mesh whose cells' bounds span a millionfold.
constexpr int kMaxStepClass = 20;

struct StepClasses {
    int top = 0;                           // the largest class of a cell with faces
    std::vector<std::uint8_t> face_class;  // per face
    // Per cell, the finest and the coarsest class of its faces: the first
    // tick level at which a face of it fires, and the first at which all do.
    std::vector<std::uint8_t> finest, coarsest;
    std::vector<std::uint8_t> taking_level;  // per cell, the first level whose ticks update it
    // Per cell, the coarsest class of the faces of the cells a change of it
    // wakes (itself and the cells whose gradients read it): they have all
    // fired again by the first tick after the change whose level reaches it.
    std::vector<std::uint8_t> waking;
    // Faces that fire; cells whose gradients and pulls they read; faces
    // that carry those pulls; cells that limit and take those fluxes.
    std::vector<std::int64_t> firing_faces, reading_cells, carrying_faces, taking_cells;
    std::vector<std::int64_t> firing_end, reading_end, carrying_end, taking_end;  // per level 0 .. top

    // The level of tick j of a step: every class at tick 0.
    int level_of_tick(std::int64_t j) const {
        int level = 0;
        while (level < top && ((j >> level) & 1) == 0) ++level;
        return level;
    }
    // The ticks face f's amounts span when it fires at tick j of n.
    static std::int64_t span(int face_class, std::int64_t j, std::int64_t n) {
        return std::min<std::int64_t>(std::int64_t{1} << face_class, n - j);
    }
    // The first tick after tick j whose level is at least `level`.
    static std::int64_t next_tick_at(int level, std::int64_t j) { return ((j >> level) + 1) << level; }
};

// The classes of a serial mesh's cells and the lists of every tick level.
StepClasses step_classes_of(const Mesh &m);
// The same on a part of a distributed mesh; collective: its ghosts' levels
// come from their owners through `exchange`, the top class from `ranks`.
StepClasses step_classes_of(const Mesh &m, GhostExchange &exchange, const Collectives &ranks);

}  // namespace dpsm
