// Load on the gRPC service: the real server in-process on 127.0.0.1:0
// (default options, so at most 2 detections at once), called by C clients at
// once, each with its own channel and thread, each sending N Detect requests
// with the whole frame as a packed cloud. Prints throughput and latency per C
// next to the in-process DetectBoxes time on the same frame.
//
//   build/tools/service_bench [--requests 20] [--clients 1,2,4]
//
// The frame is the one detector_bench times: a seeded 640x480 heap of 12
// cartons from the scene generator.
#include <grpcpp/create_channel.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "common/perception/detector.h"
#include "common/wire/cloud_wire.h"
#include "cornerpose/v1/perception_service.grpc.pb.h"
#include "server/server.h"
#include "tests/support/scene_generator.h"

namespace cornerpose {
namespace {

using Clock = std::chrono::steady_clock;

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// The q-quantile (0..1) of sorted values, nearest rank.
double Quantile(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return 0.0;
  size_t rank = static_cast<size_t>(q * static_cast<double>(sorted.size()) + 0.999999);
  rank = std::clamp<size_t>(rank, 1, sorted.size());
  return sorted[rank - 1];
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  if (n == 0) return 0.0;
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

bool ParseClients(const std::string& text, std::vector<int>* out) {
  out->clear();
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = text.find(',', start);
    const std::string item =
        text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    char* end = nullptr;
    const long c = std::strtol(item.c_str(), &end, 10);
    if (item.empty() || *end != '\0' || c < 1 || c > 256) return false;
    out->push_back(static_cast<int>(c));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return !out->empty();
}

int Usage() {
  std::fprintf(stderr, "usage: service_bench [--requests N] [--clients C1,C2,...]\n");
  return 2;
}

int Main(int argc, char** argv) {
  int requests = 20;
  std::vector<int> clients = {1, 2, 4};
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    std::string value;
    auto take = [&](const std::string& flag) {
      if (arg == flag && i + 1 < argc) {
        value = argv[++i];
        return true;
      }
      if (arg.rfind(flag + "=", 0) == 0) {
        value = arg.substr(flag.size() + 1);
        return true;
      }
      return false;
    };
    if (take("--requests")) {
      char* end = nullptr;
      const long n = std::strtol(value.c_str(), &end, 10);
      if (value.empty() || *end != '\0' || n < 1) return Usage();
      requests = static_cast<int>(n);
    } else if (take("--clients")) {
      if (!ParseClients(value, &clients)) return Usage();
    } else {
      return Usage();
    }
  }

  const BoxDims dims = {0.30, 0.20, 0.15};
  const testing::RenderedScene scene = testing::Render(testing::MakeHeapScene(dims, 12, 7));

  // In-process: median of 10 (after one warm-up), default detector options.
  DetectorOptions options;
  options.box = dims;
  std::vector<double> local_ms;
  for (int i = 0; i < 11; ++i) {
    const Clock::time_point t0 = Clock::now();
    absl::StatusOr<Detection> d = DetectBoxes(scene.cloud, options);
    const double ms = MsSince(t0);
    if (!d.ok()) {
      std::fprintf(stderr, "service_bench: DetectBoxes: %s\n", d.status().ToString().c_str());
      return 1;
    }
    if (i > 0) local_ms.push_back(ms);
  }
  const double local_median = Median(local_ms);

  server::ServerOptions server_options;
  server_options.listen_address = "127.0.0.1:0";
  absl::StatusOr<std::unique_ptr<server::RunningServer>> server =
      server::StartServer(server_options);
  if (!server.ok()) {
    std::fprintf(stderr, "service_bench: StartServer: %s\n", server.status().ToString().c_str());
    return 1;
  }
  const std::string target = "127.0.0.1:" + std::to_string((*server)->port());

  v1::DetectRequest request;
  *request.mutable_cloud() = wire::CloudToProto(scene.cloud);
  request.set_box_model("carton_s");

  auto make_stub = [&] {
    grpc::ChannelArguments args;
    args.SetMaxReceiveMessageSize(-1);
    args.SetMaxSendMessageSize(-1);
    // A channel of its own per client (no subchannel sharing).
    args.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
    auto channel = grpc::CreateCustomChannel(target, grpc::InsecureChannelCredentials(), args);
    return v1::PerceptionService::NewStub(channel);
  };

  // Warm-up: one request, so connection set-up is not timed.
  {
    auto stub = make_stub();
    grpc::ClientContext context;
    v1::DetectResponse response;
    grpc::Status s = stub->Detect(&context, request, &response);
    if (!s.ok()) {
      std::fprintf(stderr, "service_bench: warm-up Detect: %s\n", s.error_message().c_str());
      return 1;
    }
  }

  std::printf(
      "frame: 640x480 heap of 12 cartons (%zu boxes found in-process), %d requests "
      "per client, server max_concurrent_detections %d\n",
      static_cast<size_t>(DetectBoxes(scene.cloud, options)->boxes.size()), requests,
      server_options.max_concurrent_detections);
  std::printf("in-process DetectBoxes: median of 10 = %.1f ms\n\n", local_median);
  std::printf(
      "| clients | requests | throughput (req/s) | p50 (ms) | p90 (ms) | p99 (ms) | "
      "in-process (ms) |\n");
  std::printf("|---|---|---|---|---|---|---|\n");

  double p50_at_1 = -1.0;
  for (const int c : clients) {
    std::vector<std::unique_ptr<v1::PerceptionService::Stub>> stubs;
    for (int k = 0; k < c; ++k) stubs.push_back(make_stub());
    // Connect each channel before the clock starts.
    for (auto& stub : stubs) {
      grpc::ClientContext context;
      v1::ListSourcesResponse sources;
      stub->ListSources(&context, v1::ListSourcesRequest(), &sources);
    }
    std::vector<std::vector<double>> latencies(static_cast<size_t>(c));
    std::vector<int> failures(static_cast<size_t>(c), 0);
    std::vector<std::thread> threads;
    const Clock::time_point start = Clock::now();
    for (int k = 0; k < c; ++k) {
      threads.emplace_back([&, k] {
        for (int r = 0; r < requests; ++r) {
          grpc::ClientContext context;
          context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(120));
          v1::DetectResponse response;
          const Clock::time_point t0 = Clock::now();
          grpc::Status s = stubs[static_cast<size_t>(k)]->Detect(&context, request, &response);
          const double ms = MsSince(t0);
          if (s.ok()) {
            latencies[static_cast<size_t>(k)].push_back(ms);
          } else {
            ++failures[static_cast<size_t>(k)];
          }
        }
      });
    }
    for (std::thread& t : threads) t.join();
    const double wall_s = MsSince(start) / 1000.0;

    std::vector<double> all;
    int failed = 0;
    for (int k = 0; k < c; ++k) {
      all.insert(all.end(), latencies[static_cast<size_t>(k)].begin(),
                 latencies[static_cast<size_t>(k)].end());
      failed += failures[static_cast<size_t>(k)];
    }
    std::sort(all.begin(), all.end());
    if (failed > 0) std::fprintf(stderr, "service_bench: C=%d: %d requests failed\n", c, failed);
    const double p50 = Quantile(all, 0.50);
    if (c == 1) p50_at_1 = p50;
    std::printf("| %d | %zu | %.2f | %.1f | %.1f | %.1f | %.1f |\n", c, all.size(),
                static_cast<double>(all.size()) / wall_s, p50, Quantile(all, 0.90),
                Quantile(all, 0.99), local_median);
  }
  if (p50_at_1 >= 0.0) {
    std::printf("\nservice overhead (p50 at 1 client - in-process median): %.1f ms\n",
                p50_at_1 - local_median);
  }
  (*server)->Shutdown();
  return 0;
}

}  // namespace
}  // namespace cornerpose

int main(int argc, char** argv) { return cornerpose::Main(argc, argv); }
