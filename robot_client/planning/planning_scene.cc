#include "robot_client/planning/planning_scene.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "common/validation/range_check.h"
#include "robot_client/planning/place_pattern.h"

namespace cornerpose::robot_client {
namespace {

// Placed cells are shrunk by this on each side, m: touching cells stay two
// blocks, and a box lowered onto its own slot is not inside its neighbour.
constexpr double kCellShrinkM = 0.005;

collision::Obb BlockBetween(const Eigen::Vector3d& min, const Eigen::Vector3d& max) {
  collision::Obb block;
  const Eigen::Vector3d size = (max - min).cwiseMax(0.0);
  block.dims = BoxDims{size.x(), size.y(), size.z()};
  block.world_T_box.translation() = 0.5 * (min + max);
  return block;
}

}  // namespace

absl::Status CollisionCheckOptions::Validate() const {
  for (absl::Status s : {CheckRange("clearance_m", clearance_m, 0.0, 0.2),
                         CheckPositive("max_step_rad", max_step_rad, 0.2),
                         CheckPositive("tool.radius_m", tool.radius_m, 0.2),
                         CheckRange("tool.cup_compliance_m", tool.cup_compliance_m, 0.0, 0.05)}) {
    if (!s.ok()) return s;
  }
  return absl::OkStatus();
}

PlanningScene ScenePerPick(const std::vector<BoxInBase>& boxes, const BoxDims& dims,
                           const PlacePatternOptions& pattern, int slot, double floor_z_m) {
  PlanningScene scene;
  for (size_t i = 0; i < boxes.size(); ++i) {
    collision::Aabb column = collision::BoundsOf(collision::Obb{dims, boxes[i].base_T_box});
    column.min.z() = std::min(floor_z_m, column.max.z());
    scene.obstacles.push_back({absl::StrCat("detected box ", i, " (or what is under it)"),
                               BlockBetween(column.min, column.max)});
  }
  const double largest = dims.vec().maxCoeff();
  const double cell_x = pattern.columns > 1 ? pattern.spacing_x_m : largest;
  const double cell_y = pattern.rows > 1 ? pattern.spacing_y_m : largest;
  for (int s = 0; s < slot; ++s) {
    absl::StatusOr<Eigen::Isometry3d> base_T_slot = SlotPose(pattern, s);
    if (!base_T_slot.ok()) break;
    collision::Obb cell;
    cell.dims =
        BoxDims{std::max(cell_x - 2 * kCellShrinkM, 0.0), std::max(cell_y - 2 * kCellShrinkM, 0.0),
                std::max(pattern.layer_height_m - kCellShrinkM, 0.0)};
    cell.world_T_box = *base_T_slot;
    cell.world_T_box.translation() +=
        base_T_slot->linear().col(2) * (0.5 * (pattern.layer_height_m - kCellShrinkM));
    scene.obstacles.push_back({absl::StrCat("the placed box in slot ", s), cell});
  }
  return scene;
}

namespace {

// The arm's links at joints q, grown by the clearance.
std::vector<collision::Capsule> InflatedLinks(ur::ArmModel model,
                                              const Eigen::Isometry3d& flange_T_tcp,
                                              const ur::Joints& q,
                                              const CollisionCheckOptions& options) {
  std::vector<collision::Capsule> links =
      collision::ArmCapsules(model, q, flange_T_tcp, options.tool);
  for (collision::Capsule& link : links) link.radius += options.clearance_m;
  return links;
}

}  // namespace

void DropWhatTheArmOccupies(ur::ArmModel model, const Eigen::Isometry3d& flange_T_tcp,
                            const ur::Joints& q, const CollisionCheckOptions& options,
                            PlanningScene& scene) {
  const std::vector<collision::Capsule> links = InflatedLinks(model, flange_T_tcp, q, options);
  std::erase_if(scene.obstacles, [&](const SceneObstacle& obstacle) {
    return std::any_of(links.begin(), links.end(), [&](const collision::Capsule& link) {
      return collision::CapsuleTouchesBox(link, obstacle.box);
    });
  });
}

namespace {

// The first obstacle the arm or the held box at joints q comes within the
// clearance of, as a description; empty when clear.
std::string ContactAt(ur::ArmModel model, const Eigen::Isometry3d& flange_T_tcp,
                      const ur::Joints& q, const std::optional<HeldBox>& held,
                      const PlanningScene& scene, const CollisionCheckOptions& options) {
  const std::vector<collision::Capsule> links = InflatedLinks(model, flange_T_tcp, q, options);
  std::optional<collision::Obb> carried;
  if (held) {
    const Eigen::Isometry3d base_T_tcp = TcpPoseFromJoints(model, q, flange_T_tcp);
    carried = collision::Inflated(collision::Obb{held->dims, base_T_tcp * held->tcp_T_box},
                                  options.clearance_m);
  }
  for (const SceneObstacle& obstacle : scene.obstacles) {
    if (carried && collision::BoxesTouch(*carried, obstacle.box)) {
      return absl::StrCat("the held box comes within ",
                          absl::StrFormat("%.3f", options.clearance_m), " m of ", obstacle.name);
    }
    for (const collision::Capsule& link : links) {
      if (collision::CapsuleTouchesBox(link, obstacle.box)) {
        return absl::StrCat("the ", link.name, " comes within ",
                            absl::StrFormat("%.3f", options.clearance_m), " m of ", obstacle.name);
      }
    }
  }
  return "";
}

}  // namespace

absl::Status CheckFreeMove(ur::ArmModel model, const Eigen::Isometry3d& flange_T_tcp,
                           const ur::Joints& from, const ur::Joints& to,
                           const std::optional<HeldBox>& held, const PlanningScene& scene,
                           const CollisionCheckOptions& options, const std::string& what) {
  if (scene.obstacles.empty()) return absl::OkStatus();
  double largest_turn = 0.0;
  for (int i = 0; i < 6; ++i) largest_turn = std::max(largest_turn, std::abs(to[i] - from[i]));
  const int steps = std::max(1, static_cast<int>(std::ceil(largest_turn / options.max_step_rad)));
  for (int k = 0; k <= steps; ++k) {
    const double t = static_cast<double>(k) / steps;
    ur::Joints q{};
    for (int i = 0; i < 6; ++i) q[i] = from[i] + t * (to[i] - from[i]);
    const std::string contact = ContactAt(model, flange_T_tcp, q, held, scene, options);
    if (!contact.empty()) {
      const Eigen::Vector3d p = TcpPoseFromJoints(model, q, flange_T_tcp).translation();
      return absl::FailedPreconditionError(absl::StrFormat("free move %s: %s at (%.3f, %.3f, %.3f)",
                                                           what, contact, p.x(), p.y(), p.z()));
    }
  }
  return absl::OkStatus();
}

}  // namespace cornerpose::robot_client
