// The simulated cell's layout and its loads. One fixed cell, so one daemon
// configuration fits every load: a UR5e on a pedestal between two EUR
// pallets, the pick pallet (or a heap, or a bin, on it) under a depth camera
// looking straight down, and the place pallet on the far side of the robot,
// out of the camera's view.
//
//   world (z up, floor z = 0, pick pallet centred on the origin, x along its
//   1.2 m side):   pick pallet at y = 0, robot base at (0, base_y, pedestal),
//   place pallet at y = 2 base_y, camera at (0, 0, camera_height) looking down
//   (image x = world +x, image y = world -y). The robot's base frame is the
//   world frame moved to the base plate (no rotation).
//
// The load fills the pick area: up to 1.24 x 0.62 m (what a UR5e reaches
// from the pedestal), as many boxes per layer as fit.
#pragma once

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "tests/support/cell_sim/cell_world.h"

namespace cornerpose::cell_sim {

struct SimCellOptions {
  ur::ArmModel arm = ur::ArmModel::kUr5e;
  // Height of the base plate above the floor, m, [0.3, 1.5]. At 0.65 every
  // grasp of a three-layer carton_s pallet (grasp faces 0.29-0.59 m above
  // the floor, 0.36-0.06 m below the base) and its lift stay inside the
  // UR5e's singularity-free reach out to 0.85 m. A pallet load whose top is
  // higher raises it to 5 cm above that top (a cell stands its robot above
  // the load it unloads): three layers of carton_l, 0.89 m, put it at 0.94.
  double pedestal_height_m = 0.65;
  // World y of the base axis, m (the pick pallet's centre is y = 0), [-1, -0.45].
  double base_y_m = -0.49;
  // Height of the camera above the floor, m, [1.0, 3.0]. At 2.0 the top of a
  // three-layer carton pallet is 1.4 m away, the bottom layer 1.7 m, and the
  // place pallet's loads stay out of view.
  double camera_height_m = 2.0;
  // The pick area's footprint, m (centred on the pick pallet).
  double pick_length_m = 1.25;
  double pick_width_m = 0.63;
  // A heap or bin may use the pallet's whole width, m, (0.1, 0.9]: heaps
  // spread; the far boxes of a wide one may be out of reach (declined).
  double heap_width_m = 0.80;

  absl::Status Validate() const;
};

struct SimLoadOptions {
  // "pallet": layers of boxes in a grid; "heap": a heap dumped on the pallet;
  // "bin": a heap in a bin on the pallet.
  std::string kind = "pallet";
  BoxDims box{0.30, 0.20, 0.15};
  // Pallet: layers, >= 1, and the layer pattern: "grid" (every layer the
  // same, l along x) or "interlock" (every other layer turned 90 degrees).
  int layers = 3;
  std::string pattern = "grid";
  // Pallet: gap between neighbouring boxes, m, [0, 0.05]; each box is
  // jittered by up to +-1 mm and +-0.3 degrees.
  double gap_m = 0.003;
  // Heap and bin: how many boxes, [1, 60].
  int heap_boxes = 8;
  uint32_t seed = 1;

  absl::Status Validate() const;
};

struct SimCell {
  CellLayout layout;
  std::vector<testing::SceneBox> boxes;
  std::string description;  // e.g. "pallet of 3 layers x 12 boxes 0.30 x 0.20 x 0.15 (grid)"
  // The place pattern on the place pallet, in the robot's base frame: slot 0's
  // bottom centre, columns along +x, rows along +y (towards the robot),
  // enough layers for every box.
  Eigen::Vector3d place_origin_base = Eigen::Vector3d::Zero();
  int place_rows = 1, place_columns = 1, place_layers = 1;
  double place_spacing_x_m = 0.0, place_spacing_y_m = 0.0, place_layer_height_m = 0.0;
  // How high the held box is lifted above its grasp and lowered from onto
  // its slot at least, m: its bottom clears the boxes around it by 5 cm (a
  // pallet's box by its height, a heap's by its longest side). The daemon
  // raises it to clear the pile's top and checks the joint move to the
  // place pallet against the pile (a transit when it would dip).
  double lift_height_m = 0.20;
  // The daemon's selection.face_check_history: 12 for a pallet (one box
  // lying one way), 0 for heaps and bins.
  int face_check_history = 0;
};

// Builds the cell and its load; the same options give the same cell.
// INVALID_ARGUMENT for bad options or a load that does not fit the pick area.
absl::StatusOr<SimCell> MakeSimCell(const SimCellOptions& cell, const SimLoadOptions& load);

// The daemon's configuration for this cell (cornerpose.v1.RobotClientConfig
// text): the perception source, the box, the hand-eye calibration from the
// layout, a workspace around both pallets, the place pattern, a clear pose
// beside the robot, and waypoint heights that clear the pallet loads.
// `box_spec` is what goes in perception: `box_model: "carton_s"` or
// `box { l: .. b: .. h: .. }`.
absl::StatusOr<std::string> RobotClientConfigText(const SimCell& cell, const std::string& box_spec,
                                                  const std::string& source);

}  // namespace cornerpose::cell_sim
