#include "common/perception/internal/view_share.h"

#include <algorithm>
#include <boost/geometry.hpp>
#include <boost/geometry/geometries/box.hpp>
#include <boost/geometry/geometries/multi_point.hpp>
#include <boost/geometry/geometries/multi_polygon.hpp>
#include <boost/geometry/geometries/point_xy.hpp>
#include <boost/geometry/geometries/polygon.hpp>

#include "common/perception/box_pose.h"
#include "common/perception/camera_model.h"

namespace cornerpose::internal {

namespace bg = boost::geometry;
using Point = bg::model::d2::point_xy<double>;
using Polygon = bg::model::polygon<Point>;

double BoxViewShare(const CameraIntrinsics& camera, const Eigen::Isometry3d& camera_T_box,
                    const BoxDims& dims) {
  constexpr double kMinDepthM = 0.05;
  bg::model::multi_point<Point> corners;
  for (const Eigen::Vector3d& p : BoxCorners(camera_T_box, dims)) {
    if (!(p.z() > kMinDepthM)) return 0.0;
    const Eigen::Vector2d px = Project(camera, p);
    corners.emplace_back(px.x(), px.y());
  }
  Polygon outline;
  bg::convex_hull(corners, outline);
  const double whole = bg::area(outline);
  if (!(whole > 0.0)) return 0.0;
  // Pixel centres at integers: the image covers [-0.5, size - 0.5].
  const bg::model::box<Point> image(Point(-0.5, -0.5),
                                    Point(camera.width - 0.5, camera.height - 0.5));
  bg::model::multi_polygon<Polygon> inside;
  bg::intersection(outline, image, inside);
  return std::clamp(bg::area(inside) / whole, 0.0, 1.0);
}

}  // namespace cornerpose::internal
