// Load and soak: C concurrent clients (default 8), each with its own
// channel, mixing for a set time full-frame Detect, Detect on a source,
// streams, cancellations, expired deadlines, malformed requests and health
// checks. Prints throughput, p50/p99 per kind of call, status codes by kind,
// the server's resident memory at start and end, and whether the server
// still answers health and a correct request at the end.
//
//   build/tools/soak_bench --minutes 3 [--clients 8] [--source carton_s]
//       [--server HOST:PORT --server_pid PID] [--tls_ca F --tls_cert F --tls_key F]
//
// Without --server it starts the real server in-process on 127.0.0.1:0 with
// ServerOptions' defaults and the bundled carton_s frames as its source
// (resident memory is then the whole process, clients included). With
// --server it calls that server and reads /proc/PID/status of --server_pid.
#include <grpcpp/create_channel.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "common/grpc_security/tls.h"
#include "common/wire/cloud_wire.h"
#include "cornerpose/v1/perception_service.grpc.pb.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "server/server.h"
#include "tests/support/scene_generator.h"

namespace cornerpose {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  size_t rank = static_cast<size_t>(q * static_cast<double>(v.size()) + 0.999999);
  rank = std::clamp<size_t>(rank, 1, v.size());
  return v[rank - 1];
}

// VmRSS of a process in MiB, or -1.
double ResidentMiB(const std::string& pid) {
  std::ifstream in("/proc/" + pid + "/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::strtod(line.c_str() + 6, nullptr) / 1024.0;
  }
  return -1.0;
}

// What one kind of call saw.
struct Tally {
  std::vector<double> ms;
  std::map<std::string, int> codes;
};

class Recorder {
 public:
  void Add(const std::string& kind, const grpc::Status& s, double ms) {
    std::lock_guard<std::mutex> lock(mutex_);
    Tally& t = tallies_[kind];
    t.ms.push_back(ms);
    ++t.codes[CodeName(s.error_code())];
  }
  std::map<std::string, Tally> Take() {
    std::lock_guard<std::mutex> lock(mutex_);
    return tallies_;
  }
  static std::string CodeName(grpc::StatusCode code) {
    static const char* kNames[] = {"OK",
                                   "CANCELLED",
                                   "UNKNOWN",
                                   "INVALID_ARGUMENT",
                                   "DEADLINE_EXCEEDED",
                                   "NOT_FOUND",
                                   "ALREADY_EXISTS",
                                   "PERMISSION_DENIED",
                                   "RESOURCE_EXHAUSTED",
                                   "FAILED_PRECONDITION",
                                   "ABORTED",
                                   "OUT_OF_RANGE",
                                   "UNIMPLEMENTED",
                                   "INTERNAL",
                                   "UNAVAILABLE",
                                   "DATA_LOSS",
                                   "UNAUTHENTICATED"};
    const int i = static_cast<int>(code);
    return i >= 0 && i < 17 ? kNames[i] : "CODE_" + std::to_string(i);
  }

 private:
  std::mutex mutex_;
  std::map<std::string, Tally> tallies_;
};

// Requests the server must refuse with a status (never a crash or a hang).
std::vector<v1::DetectRequest> MalformedRequests(const v1::DetectRequest& good) {
  std::vector<v1::DetectRequest> out;
  v1::DetectRequest r = good;
  r.mutable_cloud()->mutable_xyz()->resize(r.cloud().xyz().size() - 5);  // ragged bytes
  out.push_back(r);
  r = good;
  r.mutable_cloud()->set_width(r.cloud().width() * 2);  // size mismatch
  out.push_back(r);
  r = good;
  r.set_box_model("no_such_box");
  out.push_back(r);
  r = good;
  r.mutable_box()->set_l(-1);
  r.mutable_box()->set_b(0.2);
  r.mutable_box()->set_h(0.1);
  out.push_back(r);
  r = good;
  r.mutable_intrinsics()->set_width(640);
  r.mutable_intrinsics()->set_height(480);
  r.mutable_intrinsics()->set_fx(1e12);
  r.mutable_intrinsics()->set_fy(std::nan(""));
  out.push_back(r);
  r = v1::DetectRequest();  // no input at all
  r.set_box_model("carton_s");
  out.push_back(r);
  r = v1::DetectRequest();
  r.mutable_depth_image()->set_width(640);
  r.mutable_depth_image()->set_height(480);
  r.mutable_depth_image()->set_encoding(v1::DEPTH_ENCODING_UINT16_MM);
  r.mutable_depth_image()->set_data(std::string(100, '\x7f'));  // too short
  r.set_box_model("carton_s");
  out.push_back(r);
  r = v1::DetectRequest();
  r.set_source("no_such_source");
  r.set_box_model("carton_s");
  out.push_back(r);
  return out;
}

int Usage() {
  std::fprintf(stderr,
               "usage: soak_bench [--minutes M] [--seconds S] [--clients C] [--source NAME]\n"
               "                  [--server HOST:PORT [--server_pid PID]]\n"
               "                  [--tls_ca FILE] [--tls_cert FILE] [--tls_key FILE]\n");
  return 2;
}

int Main(int argc, char** argv) {
  double seconds = 60;
  int clients = 8;
  std::string target, server_pid, source = "carton_s";
  ClientTlsFiles tls;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (i + 1 >= argc) return Usage();
    const std::string value = argv[++i];
    if (arg == "--minutes") {
      seconds = 60 * std::strtod(value.c_str(), nullptr);
    } else if (arg == "--seconds") {
      seconds = std::strtod(value.c_str(), nullptr);
    } else if (arg == "--clients") {
      clients = std::atoi(value.c_str());
    } else if (arg == "--server") {
      target = value;
    } else if (arg == "--server_pid") {
      server_pid = value;
    } else if (arg == "--source") {
      source = value;
    } else if (arg == "--tls_ca") {
      tls.ca = value;
    } else if (arg == "--tls_cert") {
      tls.cert = value;
    } else if (arg == "--tls_key") {
      tls.key = value;
    } else {
      return Usage();
    }
  }
  if (!(seconds > 0) || clients < 1 || clients > 256) return Usage();

  std::unique_ptr<server::RunningServer> in_process;
  if (target.empty()) {
    server::ServerOptions options;
    options.listen_address = "127.0.0.1:0";
    server::SourceSpec spec;
    spec.name = source;
    spec.directory = std::string(CORNERPOSE_SOURCE_DIR) + "/data/frames/carton_s";
    options.sources.push_back(spec);
    absl::StatusOr<std::unique_ptr<server::RunningServer>> started = server::StartServer(options);
    if (!started.ok()) {
      std::fprintf(stderr, "soak_bench: %s\n", started.status().ToString().c_str());
      return 1;
    }
    in_process = *std::move(started);
    target = "127.0.0.1:" + std::to_string(in_process->port());
    server_pid = "self";
  }

  const testing::RenderedScene scene =
      testing::Render(testing::MakeHeapScene({0.30, 0.20, 0.15}, 12, 7));
  v1::DetectRequest frame_request;
  *frame_request.mutable_cloud() = wire::CloudToProto(scene.cloud);
  frame_request.set_box_model("carton_s");
  v1::DetectRequest source_request;
  source_request.set_source(source);
  source_request.set_box_model("carton_s");
  const std::vector<v1::DetectRequest> malformed = MalformedRequests(frame_request);

  auto make_channel = [&] {
    grpc::ChannelArguments args;
    args.SetMaxReceiveMessageSize(-1);
    args.SetMaxSendMessageSize(-1);
    args.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
    absl::StatusOr<std::shared_ptr<grpc::ChannelCredentials>> credentials =
        MakeChannelCredentials(tls, &args);
    if (!credentials.ok()) {
      std::fprintf(stderr, "soak_bench: %s\n", credentials.status().ToString().c_str());
      std::exit(1);
    }
    return grpc::CreateCustomChannel(target, *credentials, args);
  };

  const double rss_start = server_pid.empty() ? -1 : ResidentMiB(server_pid);
  Recorder recorder;
  std::atomic<long> calls{0};
  const Clock::time_point start = Clock::now();
  const Clock::time_point end = start + milliseconds(static_cast<long>(seconds * 1000));
  std::vector<std::thread> threads;
  for (int c = 0; c < clients; ++c) {
    threads.emplace_back([&, c] {
      std::shared_ptr<grpc::Channel> channel = make_channel();
      auto stub = v1::PerceptionService::NewStub(channel);
      auto health = grpc::health::v1::Health::NewStub(channel);
      for (long i = c; Clock::now() < end; ++i) {
        grpc::ClientContext context;
        context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
        v1::DetectResponse response;
        const Clock::time_point t0 = Clock::now();
        grpc::Status s;
        std::string kind;
        switch (i % 10) {
          case 0:
          case 1:
          case 2:
            kind = "detect_frame";
            s = stub->Detect(&context, frame_request, &response);
            break;
          case 3:
            kind = "detect_source";
            s = stub->Detect(&context, source_request, &response);
            break;
          case 4: {
            kind = "stream_3_frames";
            v1::StreamDetectionsRequest request;
            request.set_source(source);
            request.set_box_model("carton_s");
            request.set_every_frame(i % 20 == 4);  // half catch up on kept frames
            auto reader = stub->StreamDetections(&context, request);
            int frames = 0;
            while (frames < 3 && reader->Read(&response)) ++frames;
            context.TryCancel();
            s = reader->Finish();
            if (frames == 3 && s.error_code() == grpc::StatusCode::CANCELLED) s = grpc::Status::OK;
            break;
          }
          case 5: {
            kind = "cancelled_detect";
            std::mutex m;
            std::condition_variable cv;
            bool done = false;
            stub->async()->Detect(&context, &frame_request, &response, [&](grpc::Status st) {
              std::lock_guard<std::mutex> lock(m);
              s = st;
              done = true;
              cv.notify_all();
            });
            std::this_thread::sleep_for(milliseconds(5 + (i % 7) * 10));
            context.TryCancel();
            std::unique_lock<std::mutex> lock(m);
            cv.wait(lock, [&] { return done; });
            break;
          }
          case 6: {
            kind = "expired_deadline";
            grpc::ClientContext short_context;
            short_context.set_deadline(std::chrono::system_clock::now() + milliseconds(2));
            s = stub->Detect(&short_context, frame_request, &response);
            break;
          }
          case 7:
          case 8:
            kind = "malformed";
            s = stub->Detect(&context, malformed[static_cast<size_t>(i / 10) % malformed.size()],
                             &response);
            break;
          default: {
            kind = "health";
            grpc::health::v1::HealthCheckResponse answer;
            s = health->Check(&context, grpc::health::v1::HealthCheckRequest(), &answer);
            if (s.ok() && answer.status() != grpc::health::v1::HealthCheckResponse::SERVING) {
              s = grpc::Status(grpc::StatusCode::UNAVAILABLE, "NOT_SERVING");
            }
          }
        }
        recorder.Add(kind, s, MsSince(t0));
        ++calls;
      }
    });
  }
  for (std::thread& t : threads) t.join();
  const double wall_s = MsSince(start) / 1000.0;
  const double rss_end = server_pid.empty() ? -1 : ResidentMiB(server_pid);

  // Still serving after all of it: health and a correct request.
  std::shared_ptr<grpc::Channel> channel = make_channel();
  grpc::ClientContext hc;
  hc.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  grpc::health::v1::HealthCheckResponse answer;
  const grpc::Status health_after = grpc::health::v1::Health::NewStub(channel)->Check(
      &hc, grpc::health::v1::HealthCheckRequest(), &answer);
  grpc::ClientContext dc;
  dc.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
  v1::DetectResponse detected;
  const grpc::Status detect_after =
      v1::PerceptionService::NewStub(channel)->Detect(&dc, frame_request, &detected);

  std::printf("soak: %d clients, %.0f s against %s%s\n", clients, wall_s, target.c_str(),
              in_process ? " (in-process server, default ServerOptions)" : "");
  std::printf("calls: %ld, %.1f calls/s\n\n", calls.load(), static_cast<double>(calls) / wall_s);
  std::printf(
      "| kind | calls | per s | p50 (ms) | p99 (ms) | status codes |\n|---|---|---|---|---|---|\n");
  for (const auto& [kind, tally] : recorder.Take()) {
    std::string codes;
    for (const auto& [code, n] : tally.codes) {
      codes += (codes.empty() ? "" : ", ") + code + " " + std::to_string(n);
    }
    std::printf("| %s | %zu | %.2f | %.1f | %.1f | %s |\n", kind.c_str(), tally.ms.size(),
                static_cast<double>(tally.ms.size()) / wall_s, Quantile(tally.ms, 0.5),
                Quantile(tally.ms, 0.99), codes.c_str());
  }
  std::printf("\nserver resident memory (%s): start %.1f MiB, end %.1f MiB\n",
              server_pid == "self" ? "whole process" : ("pid " + server_pid).c_str(), rss_start,
              rss_end);
  const bool serving =
      health_after.ok() && answer.status() == grpc::health::v1::HealthCheckResponse::SERVING;
  std::printf("after: health %s, Detect %s (%d boxes)\n", serving ? "SERVING" : "NOT SERVING",
              detect_after.ok() ? "OK" : detect_after.error_message().c_str(),
              detected.boxes_size());
  if (in_process) in_process->Shutdown();
  return serving && detect_after.ok() ? 0 : 1;
}

}  // namespace
}  // namespace cornerpose

int main(int argc, char** argv) { return cornerpose::Main(argc, argv); }
