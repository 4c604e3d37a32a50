// The detector's cancellation token (issue 11): a stopped token ends a
// detection with its status, from any stage, and a token that never stops
// changes nothing. Deterministic: the "caller" cancels after a fixed number
// of polls, so no test depends on the machine's speed.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <random>
#include <thread>
#include <vector>

#include "absl/time/clock.h"
#include "common/box/box_models.h"
#include "common/perception/cancel_token.h"
#include "common/perception/detector.h"
#include "tests/support/scene_generator.h"

namespace cornerpose::testing {
namespace {

using ::testing::HasSubstr;

DetectorOptions CartonOptions() {
  DetectorOptions options;
  options.box = BoxModelByName("carton_s").value();
  return options;
}

const RenderedScene& Heap() {
  static const RenderedScene* scene =
      new RenderedScene(Render(MakeHeapScene(BoxModelByName("carton_s").value(), 8, 3)));
  return *scene;
}

TEST(CancelTokenTest, DefaultNeverStops) {
  const CancelToken token;
  EXPECT_FALSE(token.Stopped());
  EXPECT_TRUE(token.Check("anything").ok());
}

TEST(CancelTokenTest, DeadlineInThePastIsDeadlineExceeded) {
  const CancelToken token(absl::Now() - absl::Milliseconds(1));
  EXPECT_TRUE(token.Stopped());
  const absl::Status s = token.Check("the edge points");
  EXPECT_EQ(s.code(), absl::StatusCode::kDeadlineExceeded);
  EXPECT_THAT(s.message(), HasSubstr("the edge points"));
}

TEST(CancelTokenTest, CancelledStaysCancelled) {
  std::atomic<bool> gone{false};
  const CancelToken token(absl::InfiniteFuture(), [&] { return gone.load(); });
  EXPECT_FALSE(token.Stopped());
  gone = true;
  EXPECT_TRUE(token.Stopped());
  gone = false;  // a caller cannot come back
  EXPECT_TRUE(token.Stopped());
  EXPECT_EQ(token.Check("x").code(), absl::StatusCode::kCancelled);
}

TEST(CancelTokenTest, CancelFromAnotherThread) {
  const CancelToken token;
  std::thread([&] { token.Cancel(); }).join();
  EXPECT_EQ(token.Check("x").code(), absl::StatusCode::kCancelled);
}

TEST(DetectorCancellationTest, ATokenThatNeverStopsChangesNothing) {
  const DetectorOptions options = CartonOptions();
  const absl::StatusOr<Detection> plain = DetectBoxes(Heap().cloud, options);
  std::atomic<int> polls{0};
  const CancelToken token(absl::Now() + absl::Hours(1), [&] {
    ++polls;
    return false;
  });
  const absl::StatusOr<Detection> with_token = DetectBoxes(Heap().cloud, options, token);
  ASSERT_TRUE(plain.ok()) << plain.status();
  ASSERT_TRUE(with_token.ok()) << with_token.status();
  ASSERT_FALSE(plain->boxes.empty());
  ASSERT_EQ(plain->boxes.size(), with_token->boxes.size());
  for (size_t i = 0; i < plain->boxes.size(); ++i) {
    EXPECT_TRUE(plain->boxes[i].camera_T_box.isApprox(with_token->boxes[i].camera_T_box, 1e-9));
    EXPECT_EQ(plain->boxes[i].score, with_token->boxes[i].score);
  }
  EXPECT_EQ(plain->edge_points.size(), with_token->edge_points.size());
  EXPECT_EQ(plain->segments.size(), with_token->segments.size());
  // Polled inside the stages, not only between them.
  EXPECT_GT(polls.load(), 50);
}

TEST(DetectorCancellationTest, AnExpiredDeadlineCostsNoDetection) {
  const CancelToken token(absl::Now() - absl::Seconds(1));
  const absl::StatusOr<Detection> d = DetectBoxes(Heap().cloud, CartonOptions(), token);
  EXPECT_EQ(d.status().code(), absl::StatusCode::kDeadlineExceeded);
}

// Cancelled after the k-th poll, for k spread over the whole detection:
// every stage stops with CANCELLED, never with a result or a crash.
TEST(DetectorCancellationTest, StopsInEveryStage) {
  std::atomic<int> total{0};
  {
    const CancelToken counting(absl::InfiniteFuture(), [&] {
      ++total;
      return false;
    });
    ASSERT_TRUE(DetectBoxes(Heap().cloud, CartonOptions(), counting).ok());
  }
  ASSERT_GT(total.load(), 10);
  for (int k : {1, 2, total.load() / 4, total.load() / 2, 3 * total.load() / 4, total.load() - 2}) {
    SCOPED_TRACE(k);
    std::atomic<int> polls{0};
    const CancelToken token(absl::InfiniteFuture(), [&] { return ++polls >= k; });
    const absl::StatusOr<Detection> d = DetectBoxes(Heap().cloud, CartonOptions(), token);
    EXPECT_EQ(d.status().code(), absl::StatusCode::kCancelled) << d.status();
    EXPECT_THAT(d.status().message(), HasSubstr("cancelled during"));
  }
}

// The k-d tree path (a merged, unorganized cloud) takes seconds on a big
// cloud: it polls inside its loop too. Cancelled from another thread once
// the detection has polled a few times.
TEST(DetectorCancellationTest, StopsTheKdTreePath) {
  PointCloud cloud;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int i = 0; i < 200000; ++i) cloud.xyz.emplace_back(u(rng), u(rng), 2.0f + u(rng));
  cloud.width = static_cast<int>(cloud.xyz.size());
  cloud.height = 1;
  DetectorOptions options = CartonOptions();
  options.project_unorganized = false;
  std::atomic<int> polls{0};
  const CancelToken token(absl::InfiniteFuture(), [&] { return ++polls > 20; });
  const absl::StatusOr<Detection> d = DetectBoxes(cloud, options, token);
  EXPECT_EQ(d.status().code(), absl::StatusCode::kCancelled) << d.status();
  // Only the loop inside the edge stage polls often enough to reach the
  // 21st poll there: checks between the stages alone would stop later.
  EXPECT_THAT(d.status().message(), HasSubstr("edge points"));
}

}  // namespace
}  // namespace cornerpose::testing
