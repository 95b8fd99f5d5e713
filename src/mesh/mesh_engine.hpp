// The engine for unstructured meshes (src/model/mesh.hpp): explicit Euler
// sub-steps over the faces of an active set of cells, the flux of each face
// written as C (h_a - h_b) with 0 <= C <= nu cos(theta) / d (docs/guarantees.md,
// "Meshes").
#pragma once

namespace dpsm {

class Engine;

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

const Engine &mesh_engine();

}  // namespace dpsm
