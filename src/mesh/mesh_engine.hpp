// The engine for unstructured meshes (src/mesh/mesh.hpp): explicit Euler
// sub-steps over the faces of an active set of cells, the flux of each face
// written as C (h_a - h_b) with 0 <= C <= nu cos(theta) / d (docs/guarantees.md,
// "Meshes").
#pragma once

#include <cstdint>
#include <vector>

#include "mesh/mesh.hpp"

namespace dpsm {

class Engine;
class Grid;

// Near rest, a face nearly parallel to the steepest slope (the slope across
// it, along its normal, at most this share of tan(theta)) carries nothing
// unless its slope exceeds tan(theta) by more than kMeshNearRest. Such a face would otherwise keep draining its
// small height difference for ever (geometrically, never to zero) while the
// error of the reconstructed gradients holds its slope a little above the
// threshold; while the pile still flows (slopes well above the threshold)
// every face carries its share, so that the flow stays isotropic.
constexpr double kMeshDeadZone = 0.25;
constexpr double kMeshNearRest = 1e-2;

// The smallest rest tolerance on a mesh: a face carries sand only when its
// slope exceeds tan(theta) by more than this share (or the host's tolerance,
// when larger). The reconstructed gradients are exact for planes only; on a
// pile their error is of the order of the cell size (about 1 % of tan(theta)
// at 4,000 cells), and chasing the last 1e-6 of the slope within that error
// took the column collapse 50 time units to rest on 7,200 jittered triangles
// where it takes 1.8 at 1e-4 (docs/guide_meshes.md).
constexpr double kMeshRestTolerance = 1e-4;

// The sub-step is this share of the largest monotone one, so that every
// sub-step in which sand moves lowers sum A (h - L)^2 by a bounded amount.
constexpr double kMeshStepSafety = 0.9;

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
    void cool_all() {
        for (const std::int64_t c : hot_list) hot[c] = 0;
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
    void wake_around(const Mesh &mesh, std::int64_t c) {
        if (all_hot) return;
        wake(c);
        for (std::int64_t k = mesh.grad_start[c]; k < mesh.grad_start[c + 1]; ++k) wake(mesh.grad_cells[k]);
    }
    bool may_move() const { return all_hot || !hot_list.empty(); }
};

const Engine &mesh_engine();

}  // namespace dpsm
