// What a cornerpose server is started with.
#pragma once

#include <string>
#include <vector>

namespace cornerpose::server {

// A directory of recorded frames served as a named source (see
// directory_source.h); `cornerpose_server --source NAME=DIR[:FPS[:loop|once]]`.
struct SourceSpec {
  // What DetectRequest.source names; unique, non-empty.
  std::string name;
  std::string directory;
  // Frames per second of the replay; > 0.
  double fps = 5.0;
  // Replay forever (true) or once.
  bool loop = true;
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
  // Frame sources requests can name. A source that fails (a missing
  // directory, say) is listed as FAILED; the server still starts.
  std::vector<SourceSpec> sources;
};

}  // namespace cornerpose::server
