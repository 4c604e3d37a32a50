// What a cornerpose server is started with.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "common/box/box_models.h"
#include "common/perception/detector.h"

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
  // The detector options every request starts from (its box is unused: a
  // request names the box).
  DetectorOptions detector;
  // Box sizes requests can name as box_model, besides the built-in models
  // (a name here takes precedence).
  BoxModels box_models;
  // Frame sources requests can name. A source that fails (a missing
  // directory, say) is listed as FAILED; the server still starts.
  std::vector<SourceSpec> sources;
};

}  // namespace cornerpose::server
