// cornerpose: the command-line tool.
//
//   cornerpose detect --cloud FILE --box L,B,H|NAME --json OUT [--ply OUT] [--png OUT] ...
//   cornerpose client detect --server ADDR --cloud FILE --box L,B,H|NAME [--json OUT] ...
//   cornerpose client stream --server ADDR --source NAME --box L,B,H|NAME [--frames N] ...
//   cornerpose client sources|health --server ADDR
//
// Run `cornerpose detect --help` for every option.
#include <cstdio>
#include <string>
#include <vector>

#include "common/process/frame_memory.h"
#include "tools/client_command.h"
#include "tools/detect_command.h"

namespace {

constexpr char kUsage[] =
    "usage: cornerpose <command> [options]\n"
    "commands:\n"
    "  detect   find edges, corners and box poses in a point cloud file\n"
    "  client   talk to a cornerpose server: detect, stream, sources, health\n"
    "run 'cornerpose <command> --help' for the options of a command\n";

}  // namespace

int main(int argc, char** argv) {
  cornerpose::KeepFrameMemoryInProcess();
  if (argc < 2) {
    std::fputs(kUsage, stderr);
    return 2;
  }
  const std::string command = argv[1];
  std::vector<std::string> args(argv + 2, argv + argc);
  if (command == "detect") return cornerpose::tools::RunDetect(args);
  if (command == "client") return cornerpose::tools::RunClient(args);
  if (command == "--help" || command == "-h" || command == "help") {
    std::fputs(kUsage, stdout);
    return 0;
  }
  std::fprintf(stderr, "cornerpose: unknown command '%s'\n%s", command.c_str(), kUsage);
  return 2;
}
