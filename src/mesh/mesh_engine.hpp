// The engine for unstructured meshes (src/model/mesh.hpp): explicit Euler
// sub-steps of the gradient flow of the faces' energy, limited by Zalesak's
// flux-corrected transport towards a monotone two-point flux C (h_a - h_b)
// with 0 <= C <= nu cos(theta) / d, over the faces of an active set of cells
// (docs/guarantees.md, "Meshes").
#pragma once

namespace dpsm {

class Engine;

// The sub-step is this share of the largest one for which the monotone
// flux's update is a weighted mean of the old heights (docs/guarantees.md).
constexpr double kMeshStepSafety = 0.9;

const Engine &mesh_engine();

}  // namespace dpsm
