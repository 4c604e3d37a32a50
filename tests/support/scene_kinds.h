// The named scene kinds of the recorded-frame sets (make_frames --kind) as
// one table, so the tools that render sets and the detector's benchmark
// draw the same scenes.
#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "common/box/box_types.h"
#include "tests/support/scene_generator.h"

namespace cornerpose::testing {

// Frame i of a set of `kind`, with the scorer's scene type in *type:
//   isolated  1-4 boxes apart;  heap  6-13 touching, stacked and tilted boxes;
//   pallet    a grid with 2-4 mm gaps, 1-2 layers;
//   touching  a pallet of touching cartons (0-3 mm gaps) at one layer or two
//             heights, with 1-3 boxes of another size on the top layer
//             (touching1 / touching2: one layer / two heights; type "pallet");
//   cell      the demo cell's view, with this placement's lens.
absl::StatusOr<Scene> MakeSceneOfKind(const std::string& kind, const BoxDims& dims, int i,
                                      uint32_t seed, const CameraPlacement& place,
                                      std::string* type);

// The largest grid of cartons (l along the pallet's 1.2 m side) on a EUR
// pallet, overhanging it by at most 5 %.
void PalletGrid(const BoxDims& dims, int* rows, int* cols);

}  // namespace cornerpose::testing
