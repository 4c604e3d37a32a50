#include "tests/support/scene_kinds.h"

#include <algorithm>

namespace cornerpose::testing {

void PalletGrid(const BoxDims& dims, int* rows, int* cols) {
  *cols = std::max(1, static_cast<int>(1.26 / (dims.l + 0.003)));
  *rows = std::max(1, static_cast<int>(0.84 / (dims.b + 0.003)));
}

absl::StatusOr<Scene> MakeSceneOfKind(const std::string& kind, const BoxDims& dims, int i,
                                      uint32_t seed, const CameraPlacement& place,
                                      std::string* type) {
  *type = kind;
  if (kind == "isolated") return MakeIsolatedScene(dims, 1 + i % 4, seed, place);
  if (kind == "heap") return MakeHeapScene(dims, 6 + i % 8, seed, place);
  if (kind == "cell") {
    Scene scene = MakeCellScene(dims, 5 + i % 4, seed);
    scene.camera = place.intrinsics;  // the cell's fixed mounting, this sensor's lens
    return scene;
  }
  if (kind == "pallet") {
    return MakePalletScene(dims, 3 + i % 2, 2 + i % 3, 1 + i % 2, 0.002 + 0.001 * (i % 3), i % 4,
                           seed, place);
  }
  if (kind == "touching" || kind == "touching1" || kind == "touching2") {
    *type = "pallet";
    int rows, cols;
    PalletGrid(dims, &rows, &cols);
    // Sometimes a row or column fewer than fits, so the layer's outline varies.
    rows = std::max(2, rows - (i / 4) % 2);
    cols = std::max(2, cols - (i / 8 + i) % 2);
    const int layers = kind == "touching1" ? 1 : kind == "touching2" ? 2 : 1 + i % 2;
    // Two heights: part of the top layer taken away (a quarter to a half).
    const int removed = layers == 1 ? 0 : std::max(1, rows * cols * (1 + (i / 4) % 2) / 4);
    // 1-3 boxes of another size, at most a fifth of the layer.
    const int distractors = std::min(1 + i % 3, std::max(1, rows * cols / 5));
    const double gap = 0.001 * ((i + i / 4) % 4);  // 0-3 mm
    return MakeDistractorPalletScene(dims, rows, cols, layers, gap, removed, distractors, seed,
                                     place);
  }
  return absl::InvalidArgumentError("unknown --kind " + kind);
}

}  // namespace cornerpose::testing
