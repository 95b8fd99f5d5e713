// The volume each face carried during the last step (dpsm_get_face_fluxes),
// kept when the host asks for it (dpsm_set_face_flux_recording). The sweeps
// add what their faces carry; nothing is cleared between steps: on a 2D grid
// each tile of the active set owns its faces and notes the step whose
// fluxes they hold, so that a step that visits a few tiles costs those
// tiles only, and faces of tiles a step did not visit read as 0.
#pragma once

#include <cstdint>
#include <vector>

namespace dpsm {

struct FaceFluxes {
    // Positive towards increasing x (y): x[i + (nx + 1) j] is the face on the
    // low side of cell (i, j) (i = nx: the high side of the last column),
    // y[i + nx j] the face on the low side of cell (i, j) (j = ny: the high
    // side of the last row; 2D only).
    std::vector<double> x, y;
    std::vector<std::uint64_t> tile_step;  // 2D: per tile, the step whose fluxes its faces hold
    std::uint64_t step = 0;                // the step being (or last) recorded; counts from 1
    bool available = true;                 // false after a step that relaxed to rest (no face carried its sand)
};

}  // namespace dpsm
