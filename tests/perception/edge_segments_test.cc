#include "common/perception/edge_segments.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <iostream>
#include <numbers>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "common/perception/internal/parallel.h"

namespace cornerpose {
namespace {

// Points every `step` along x in [x0, x1] at y = 0, z = 1.
void AddRun(double x0, double x1, double step, std::vector<Eigen::Vector3f>* pts) {
  for (double x = x0; x <= x1 + 1e-9; x += step) {
    pts->emplace_back(static_cast<float>(x), 0.0f, 1.0f);
  }
}

int IndexOfX(const std::vector<Eigen::Vector3f>& pts, double x) {
  for (int i = 0; i < static_cast<int>(pts.size()); ++i) {
    if (std::abs(pts[i].x() - x) < 1e-5) return i;
  }
  return -1;
}

TEST(FindExtremitiesTest, StopsAtAGapWiderThanTheRadius) {
  std::vector<Eigen::Vector3f> pts;
  AddRun(0.0, 0.20, 0.002, &pts);
  AddRun(0.25, 0.45, 0.002, &pts);  // 5 cm gap, radius 2 cm
  std::mt19937 rng(3);
  std::shuffle(pts.begin(), pts.end(), rng);
  const int reference = IndexOfX(pts, 0.08);
  ASSERT_GE(reference, 0);
  const auto [e1, e2] = FindExtremities(pts, reference, 0.02);
  // e1 is the nearer extremity (x = 0), e2 the one on the other side (x = 0.2).
  EXPECT_NEAR(pts[e1].x(), 0.0, 1e-5);
  EXPECT_NEAR(pts[e2].x(), 0.20, 1e-5);
}

TEST(FindExtremitiesTest, ReferenceInTheSecondRunStaysInIt) {
  std::vector<Eigen::Vector3f> pts;
  AddRun(0.0, 0.20, 0.002, &pts);
  AddRun(0.25, 0.45, 0.002, &pts);
  const int reference = IndexOfX(pts, 0.40);
  ASSERT_GE(reference, 0);
  const auto [e1, e2] = FindExtremities(pts, reference, 0.02);
  EXPECT_NEAR(pts[e1].x(), 0.45, 1e-5);
  EXPECT_NEAR(pts[e2].x(), 0.25, 1e-5);
}

TEST(FindExtremitiesTest, SpansAGapNarrowerThanTheRadius) {
  std::vector<Eigen::Vector3f> pts;
  AddRun(0.0, 0.20, 0.002, &pts);
  AddRun(0.215, 0.45, 0.002, &pts);  // 1.5 cm gap, radius 2 cm
  std::mt19937 rng(4);
  std::shuffle(pts.begin(), pts.end(), rng);
  const int reference = IndexOfX(pts, 0.08);
  ASSERT_GE(reference, 0);
  const auto [e1, e2] = FindExtremities(pts, reference, 0.02);
  EXPECT_NEAR(pts[e1].x(), 0.0, 1e-5);
  EXPECT_NEAR(pts[e2].x(), 0.45, 1e-3);
}

TEST(FindExtremitiesTest, ReferenceAtAnEndIsItsOwnSecondExtremity) {
  std::vector<Eigen::Vector3f> pts;
  AddRun(0.0, 0.20, 0.002, &pts);
  const int reference = IndexOfX(pts, 0.0);
  const auto [e1, e2] = FindExtremities(pts, reference, 0.02);
  EXPECT_NEAR(pts[e1].x(), 0.20, 1e-5);
  EXPECT_EQ(e2, reference);
}

TEST(FindExtremitiesTest, DegenerateInputs) {
  EXPECT_EQ(FindExtremities({}, 0, 0.02), std::make_pair(0, 0));
  const std::vector<Eigen::Vector3f> one = {{0, 0, 1}};
  EXPECT_EQ(FindExtremities(one, 0, 0.02), std::make_pair(0, 0));
  EXPECT_EQ(FindExtremities(one, 5, 0.02), std::make_pair(5, 5));
}

// A noisy band of edge points around the segment a -> b: `per_m` points per
// metre, Gaussian offsets of sigma across it.
void AddBand(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double per_m, double sigma,
             std::mt19937& rng, std::vector<Eigen::Vector3f>* pts) {
  const Eigen::Vector3d d = (b - a).normalized();
  const Eigen::Vector3d u = d.unitOrthogonal(), v = d.cross(u);
  std::uniform_real_distribution<double> along(0.0, (b - a).norm());
  std::normal_distribution<double> across(0.0, sigma);
  const int n = static_cast<int>(per_m * (b - a).norm());
  for (int i = 0; i < n; ++i) {
    pts->push_back((a + along(rng) * d + across(rng) * u + across(rng) * v).cast<float>());
  }
}

// Distance from p to the segment a-b.
double DistanceToSegment(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                         const Eigen::Vector3d& b) {
  const Eigen::Vector3d d = b - a;
  const double t = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
  return (a + t * d - p).norm();
}

// True when the segment's two ends match {a, b} in either order within tol.
bool EndsMatch(const EdgeSegment& s, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
               double tol) {
  const Eigen::Vector3d e1 = s.end1.cast<double>(), e2 = s.end2.cast<double>();
  return ((e1 - a).norm() < tol && (e2 - b).norm() < tol) ||
         ((e1 - b).norm() < tol && (e2 - a).norm() < tol);
}

TEST(FitEdgeSegmentsTest, CollinearRunsWithAGapStayTwoSegments) {
  std::mt19937 rng(11);
  std::vector<Eigen::Vector3f> pts;
  const Eigen::Vector3d a0(-0.30, 0.05, 1.1), a1(0.0, 0.05, 1.1);
  const Eigen::Vector3d b0(0.05, 0.05, 1.1), b1(0.30, 0.05, 1.1);  // 5 cm gap
  AddBand(a0, a1, 1500, 0.002, rng, &pts);
  AddBand(b0, b1, 1500, 0.002, rng, &pts);
  std::shuffle(pts.begin(), pts.end(), rng);
  const absl::StatusOr<std::vector<EdgeSegment>> segments =
      FitEdgeSegments(pts, EdgeSegmentOptions{});
  ASSERT_TRUE(segments.ok()) << segments.status();
  ASSERT_EQ(segments->size(), 2u);
  const EdgeSegment& s = (*segments)[0];
  const EdgeSegment& t = (*segments)[1];
  const bool s_is_a = s.point.x() < 0.0f;
  const EdgeSegment& sa = s_is_a ? s : t;
  const EdgeSegment& sb = s_is_a ? t : s;
  EXPECT_TRUE(EndsMatch(sa, a0, a1, 0.01)) << sa.end1.transpose() << " / " << sa.end2.transpose();
  EXPECT_TRUE(EndsMatch(sb, b0, b1, 0.01)) << sb.end1.transpose() << " / " << sb.end2.transpose();
  for (const EdgeSegment* seg : {&sa, &sb}) {
    EXPECT_NEAR(seg->direction.norm(), 1.0f, 1e-5f);
    EXPECT_NEAR(std::abs(seg->direction.x()), 1.0f, 0.01f);
    // end1 -> end2 runs along direction.
    EXPECT_GT((seg->end2 - seg->end1).dot(seg->direction), 0.0f);
    EXPECT_GT(seg->num_points, 300);
  }
}

struct Rectangle {
  std::array<Eigen::Vector3d, 4> corners;
};

// A 0.30 x 0.20 rectangle turned and tilted in front of the camera.
Rectangle TiltedRectangle() {
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  const Eigen::Vector3d c(0.05, -0.02, 1.2);
  Rectangle r;
  r.corners = {c + R * Eigen::Vector3d(-0.15, -0.10, 0), c + R * Eigen::Vector3d(0.15, -0.10, 0),
               c + R * Eigen::Vector3d(0.15, 0.10, 0), c + R * Eigen::Vector3d(-0.15, 0.10, 0)};
  return r;
}

std::vector<Eigen::Vector3f> RectangleOutline(const Rectangle& r, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<Eigen::Vector3f> pts;
  for (int k = 0; k < 4; ++k) AddBand(r.corners[k], r.corners[(k + 1) % 4], 1500, 0.002, rng, &pts);
  std::shuffle(pts.begin(), pts.end(), rng);
  return pts;
}

TEST(FitEdgeSegmentsTest, RectangleOutlineGivesFourSides) {
  const Rectangle r = TiltedRectangle();
  const EdgeSegmentOptions options;
  const absl::StatusOr<std::vector<EdgeSegment>> segments =
      FitEdgeSegments(RectangleOutline(r, 5), options);
  ASSERT_TRUE(segments.ok()) << segments.status();
  ASSERT_EQ(segments->size(), 4u);
  // A side fitted after its perpendicular neighbours has lost the points in
  // their removal tubes (ransac_threshold_m * removal_scale = 1.5 cm) at
  // each end: by design (the clubbing's end_gap_m bridges it), so the
  // length may fall short by up to two tubes. Sides fitted first keep their
  // full length, give or take the 1 cm RANSAC tube across the corner bands.
  const double tube = options.ransac_threshold_m * options.removal_scale;
  std::array<int, 4> found{};
  for (size_t n = 0; n < segments->size(); ++n) {
    const EdgeSegment& s = (*segments)[n];
    // Which side it lies on: both ends within 1 cm of that side.
    int side = -1;
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d &a = r.corners[k], &b = r.corners[(k + 1) % 4];
      if (DistanceToSegment(s.end1.cast<double>(), a, b) < 0.01 &&
          DistanceToSegment(s.end2.cast<double>(), a, b) < 0.01) {
        side = k;
      }
    }
    ASSERT_GE(side, 0) << s.end1.transpose() << " / " << s.end2.transpose();
    ++found[side];
    const Eigen::Vector3d a = r.corners[side], b = r.corners[(side + 1) % 4];
    const double true_length = (b - a).norm();
    std::cout << "segment " << n << " on side " << side << ": length " << s.length() << " of "
              << true_length << "\n";
    EXPECT_GT(std::abs(s.direction.cast<double>().dot((b - a).normalized())),
              std::cos(1.0 * std::numbers::pi / 180.0));
    EXPECT_TRUE(EndsMatch(s, a, b, tube + 0.01))
        << s.end1.transpose() << " / " << s.end2.transpose();
    EXPECT_LT(s.length(), true_length + 0.015);
    EXPECT_GT(s.length(), true_length - 2.0 * tube - 0.005);
    if (n == 0) {
      EXPECT_NEAR(s.length(), true_length, 0.015);
    }
  }
  EXPECT_EQ(found, (std::array<int, 4>{1, 1, 1, 1}));
}

TEST(FitEdgeSegmentsTest, SameSeedSameSegments) {
  const std::vector<Eigen::Vector3f> pts = RectangleOutline(TiltedRectangle(), 6);
  EdgeSegmentOptions options;
  options.seed = 1234;
  const auto a = FitEdgeSegments(pts, options);
  const auto b = FitEdgeSegments(pts, options);
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_FALSE(a->empty());
  ASSERT_EQ(a->size(), b->size());
  for (size_t i = 0; i < a->size(); ++i) {
    EXPECT_EQ((*a)[i].end1, (*b)[i].end1);
    EXPECT_EQ((*a)[i].end2, (*b)[i].end2);
    EXPECT_EQ((*a)[i].direction, (*b)[i].direction);
    EXPECT_EQ((*a)[i].num_points, (*b)[i].num_points);
  }
}

// The same segments, end for end, in the same order.
void ExpectSameSegments(const std::vector<EdgeSegment>& a, const std::vector<EdgeSegment>& b,
                        const std::string& label) {
  ASSERT_EQ(a.size(), b.size()) << label;
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].end1, b[i].end1) << label;
    EXPECT_EQ(a[i].end2, b[i].end2) << label;
    EXPECT_EQ(a[i].num_points, b[i].num_points) << label;
  }
}

// The RANSAC iterations run on several threads (internal::ForkJoin); what
// they find must not depend on how many.
TEST(FitEdgeSegmentsTest, SameSegmentsOnAnyNumberOfThreads) {
  std::vector<Eigen::Vector3f> pts = RectangleOutline(TiltedRectangle(), 6);
  const std::vector<Eigen::Vector3f> more = RectangleOutline(TiltedRectangle(), 4);
  for (const Eigen::Vector3f& p : more) pts.push_back(p + Eigen::Vector3f(0.5f, 0.1f, 0.05f));
  EdgeSegmentOptions one;
  one.num_threads = 1;
  EdgeSegmentOptions three;
  three.num_threads = 3;
  const auto a = FitEdgeSegments(pts, one);
  const auto b = FitEdgeSegments(pts, three);
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_GE(a->size(), 8u);
  ExpectSameSegments(*a, *b, "3 threads");
}

// The same with the iterations on shared loops (internal::SharedLoops), as
// the detector runs them: a helper that joins late, or two from the start,
// change nothing either.
TEST(FitEdgeSegmentsTest, SameSegmentsOnSharedLoopsWithLateAndEarlyHelpers) {
  std::vector<Eigen::Vector3f> pts = RectangleOutline(TiltedRectangle(), 6);
  const std::vector<Eigen::Vector3f> more = RectangleOutline(TiltedRectangle(), 4);
  for (const Eigen::Vector3f& p : more) pts.push_back(p + Eigen::Vector3f(0.5f, 0.1f, 0.05f));
  EdgeSegmentOptions one;
  one.num_threads = 1;
  const auto reference = FitEdgeSegments(pts, one);
  ASSERT_TRUE(reference.ok());
  ASSERT_GE(reference->size(), 8u);
  for (const int helpers : {0, 1, 2}) {
    internal::SharedLoops shared;
    std::vector<std::jthread> threads;
    for (int h = 0; h < helpers; ++h) {
      threads.emplace_back([&shared, h] {
        // The first helper arrives once the fit is under way.
        if (h == 0) std::this_thread::sleep_for(std::chrono::milliseconds(2));
        shared.Help();
      });
    }
    const auto got = FitEdgeSegments(pts, one, &shared);
    shared.Close();
    ASSERT_TRUE(got.ok());
    ExpectSameSegments(*reference, *got, std::to_string(helpers) + " helpers");
  }
}

// Every index of every loop runs exactly once, whoever takes it.
TEST(SharedLoopsTest, EveryIndexRunsOnceWithHelpers) {
  internal::SharedLoops shared;
  std::vector<std::jthread> helpers;
  for (int h = 0; h < 2; ++h) helpers.emplace_back([&shared] { shared.Help(); });
  for (int n : {1, 7, 8, 9, 100, 1000}) {
    std::vector<std::atomic<int>> runs(n);
    shared.Run(n, 8, [&](int begin, int end) {
      for (int i = begin; i < end; ++i) runs[i].fetch_add(1);
    });
    for (int i = 0; i < n; ++i) ASSERT_EQ(runs[i].load(), 1) << "n " << n << " index " << i;
  }
  shared.Close();
}

TEST(FitEdgeSegmentsTest, EmptyAndSparseInputGiveNoSegments) {
  const auto none = FitEdgeSegments({}, EdgeSegmentOptions{});
  ASSERT_TRUE(none.ok()) << none.status();
  EXPECT_TRUE(none->empty());
  // Fewer points than min_points.
  std::vector<Eigen::Vector3f> few;
  AddRun(0.0, 0.05, 0.01, &few);
  const auto sparse = FitEdgeSegments(few, EdgeSegmentOptions{});
  ASSERT_TRUE(sparse.ok()) << sparse.status();
  EXPECT_TRUE(sparse->empty());
}

TEST(FitEdgeSegmentsTest, ScatteredPointsGiveNoLongSegments) {
  // Uniform noise in a 30 cm cube: no line of 12+ points within 1 cm.
  std::mt19937 rng(8);
  std::uniform_real_distribution<float> u(-0.15f, 0.15f);
  std::vector<Eigen::Vector3f> pts;
  for (int i = 0; i < 300; ++i) pts.emplace_back(u(rng), u(rng), 1.0f + u(rng));
  const auto segments = FitEdgeSegments(pts, EdgeSegmentOptions{});
  ASSERT_TRUE(segments.ok()) << segments.status();
  EXPECT_TRUE(segments->empty()) << segments->size() << " segments";
}

TEST(EdgeSegmentOptionsTest, InvalidOptionsAreRefused) {
  EXPECT_TRUE(EdgeSegmentOptions{}.Validate().ok());
  std::vector<Eigen::Vector3f> pts;
  AddRun(0.0, 0.2, 0.002, &pts);
  EdgeSegmentOptions o;
  o.ransac_threshold_m = 0.0;
  EXPECT_EQ(FitEdgeSegments(pts, o).status().code(), absl::StatusCode::kInvalidArgument);
  o = EdgeSegmentOptions{};
  o.gap_m = -0.01;
  EXPECT_EQ(o.Validate().code(), absl::StatusCode::kInvalidArgument);
  o = EdgeSegmentOptions{};
  o.sample_max_m = o.sample_min_m;
  EXPECT_EQ(o.Validate().code(), absl::StatusCode::kInvalidArgument);
  o = EdgeSegmentOptions{};
  o.removal_scale = 0.5;
  EXPECT_EQ(o.Validate().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace cornerpose
