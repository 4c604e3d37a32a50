// What a cornerpose server is started with.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "common/box/box_models.h"
#include "common/perception/detector.h"
#include "server/http/http_options.h"

namespace cornerpose::server {

// Where a named source's frames come from.
enum class SourceKind {
  // A directory of recorded frames (directory_source.h).
  kDirectory,
  // A live OpenNI2 device (openni2_source.h); `uri` names it, "" = any.
  kOpenNi2Device,
  // An .oni recording played back through OpenNI2; `uri` is the file.
  kOniFile,
};

// A frame source the server serves by name; `cornerpose_server --source`
// NAME=DIR[:FPS[:loop|once]], NAME=openni2:[URI] or
// NAME=oni:FILE[:SPEED][:loop|once] (see source_spec.h).
struct SourceSpec {
  // What DetectRequest.source names; unique, non-empty.
  std::string name;
  SourceKind kind = SourceKind::kDirectory;
  // kDirectory: the directory.
  std::string directory{};
  // kOpenNi2Device: the device URI ("" = the first device OpenNI2 lists);
  // kOniFile: the .oni file.
  std::string uri{};
  // kDirectory: frames per second of the replay; > 0.
  double fps = 5.0;
  // kDirectory and kOniFile: replay forever (true) or once.
  bool loop = true;
  // kOniFile: playback rate relative to the recording; > 0.
  double playback_speed = 1.0;
};

struct ServerOptions {
  // host:port to listen on; port 0 picks a free port (tests).
  std::string listen_address = "0.0.0.0:50051";
  // Largest request or response, bytes. A VGA cloud is 3.7 MB, above gRPC's
  // 4 MiB default once framed, so the default leaves room for larger frames.
  int max_message_bytes = 64 * 1024 * 1024;
  // Detections run at once; more wait in a queue. Each uses the detector's
  // worker threads, so this times num_threads should not exceed the cores.
  int max_concurrent_detections = 2;
  // Connections older than this are asked to reconnect (gRPC GOAWAY), so
  // clients re-resolve the service name and find new replicas (behind a
  // headless Kubernetes Service); calls in flight, streams included, run on
  // undisturbed. Seconds; 0 = never.
  int max_connection_age_s = 0;
  // Admission control (see README, "Admission control"). Detect requests
  // that may wait for a worker; one more is RESOURCE_EXHAUSTED. Each waiting
  // request holds its message, so (max_concurrent_detections +
  // max_queued_detections) x max_message_bytes bounds request memory.
  // 0 to 10000.
  int max_queued_detections = 8;
  // StreamDetections calls open at once; one more is RESOURCE_EXHAUSTED.
  // Each holds a thread and at most one queued detection. 0 to 10000.
  int max_streams = 16;
  // Deadline given to a Detect that brings none, milliseconds; 1 to
  // max_deadline_ms.
  int default_deadline_ms = 10000;
  // Longest a Detect may run whatever deadline it brings, milliseconds;
  // 1 to 3600000.
  int max_deadline_ms = 60000;
  // On shutdown, how long RPCs in flight may finish before they are
  // cancelled, milliseconds; 0 to 600000. Streams are ended at once.
  int shutdown_grace_ms = 5000;
  // Health turns NOT_SERVING when detections are waiting or running and
  // none has finished for this long (a wedged pool), and SERVING again once
  // one does. Milliseconds; 10 to 3600000. Longer than the slowest
  // detection the server accepts.
  int stall_timeout_ms = 15000;

  // TLS (see README, "TLS"). PEM files; all empty = plaintext. tls_cert and
  // tls_key go together; tls_client_ca (needs both) makes client
  // certificates required and verified against it.
  std::string tls_cert{};
  std::string tls_key{};
  std::string tls_client_ca{};
  // gRPC server reflection (grpcurl without the protos). Off in production.
  bool enable_reflection = true;
  // StreamDetections and Detect on a source: a frame showing the same scene
  // as the last frame detected on (CompareFrames) gets that detection
  // without a detector run (README, "Streams that keep up").
  bool carry_unchanged_frames = true;

  // The detector options every request starts from (its box is unused: a
  // request names the box).
  DetectorOptions detector;
  // Box sizes requests can name as box_model, besides the built-in models
  // (a name here takes precedence).
  BoxModels box_models;
  // Frame sources requests can name. A source that fails (a missing
  // directory, say) is listed as FAILED; the server still starts.
  std::vector<SourceSpec> sources;
  // The HTTP port: the web view, its JSON API and /metrics (http_options.h).
  HttpOptions http;

  // OK, or INVALID_ARGUMENT naming the first field out of range (its value
  // and range) or a TLS file set without its partner. Sources and the
  // detector are checked by their own loaders.
  absl::Status Validate() const;
};

}  // namespace cornerpose::server
