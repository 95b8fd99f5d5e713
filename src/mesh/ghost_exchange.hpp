// How a part of a distributed mesh gets its ghosts' values from the ranks
// that own them: any per-cell array, over one of two sets of ghosts (every
// ghost, or those across a face from an owned cell), as PETSc's star forest
// moves any field over one graph. The grid's Distribution implements it
// (mpi/distributed_mesh.cpp); the mesh engine says what moves and when
// (mesh/mesh_parts.hpp).
#pragma once

#include <cstdint>
#include <vector>

namespace dpsm {

// One value per cell of a mesh's part, of one of three types; with every
// pointer null the field is absent (neither sent nor compared nor written),
// so that a field keeps its place in a list whether or not a scene uses it.
struct GhostField {
    double *f64 = nullptr;
    float *f32 = nullptr;
    std::uint8_t *u8 = nullptr;

    bool present() const { return f64 || f32 || u8; }
    double get(std::int64_t c) const {
        return f64 ? f64[c] : f32 ? static_cast<double>(f32[c]) : static_cast<double>(u8[c]);
    }
    void set(std::int64_t c, double v) const {
        if (f64)
            f64[c] = v;
        else if (f32)
            f32[c] = static_cast<float>(v);
        else
            u8[c] = static_cast<std::uint8_t>(v);
    }
};

class GhostExchange {
public:
    enum Ghosts { kEveryGhost = 0, kFaceGhosts = 1 };  // the second: across a face from an owned cell
    virtual ~GhostExchange() = default;

    // Collective: each ghost of `ghosts` takes its owner's values of
    // `fields` where they changed since they were last sent this way (only
    // those travel: a part whose cells near its neighbours are at rest sends
    // nothing). `computed` names the owned cells whose values may have
    // changed (null: any). The ghosts whose values changed are appended to
    // `changed_ghosts`. A list keeps its fields in the same places from one
    // call to the next; calls that follow each other over one set of ghosts
    // send different first fields, so that their messages never mix.
    virtual void send_changed(Ghosts ghosts, const std::vector<GhostField> &fields,
                              const std::vector<std::int64_t> *computed, std::vector<std::int64_t> &changed_ghosts) = 0;
    // Collective: every ghost of `ghosts` takes its owner's values of
    // `fields`, whole (after a host's edit). With `remember`, what was sent
    // becomes what send_changed compares the same list with.
    virtual void send_all(Ghosts ghosts, const std::vector<GhostField> &fields, bool remember) = 0;
};

}  // namespace dpsm
