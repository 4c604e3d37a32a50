#include "tools/client_command.h"

#include <cstdio>
#include <string>

#include "tools/client/client_commands.h"

namespace cornerpose::tools {
namespace {

constexpr char kUsage[] =
    "usage: cornerpose client <command> [options]\n"
    "commands:\n"
    "  detect   run the detector of a cornerpose server on a point cloud file or\n"
    "           on a frame of one of its sources\n"
    "  stream   detections on every new frame of one of the server's sources\n"
    "  sources  list the server's frame sources and their state\n"
    "  health   exit 0 when the server reports SERVING (gRPC health checking)\n"
    "run 'cornerpose client <command> --help' for the options of a command\n";

}  // namespace

int RunClient(const std::vector<std::string>& args) {
  if (args.empty()) {
    std::fputs(kUsage, stderr);
    return 2;
  }
  const std::string& command = args[0];
  const std::vector<std::string> rest(args.begin() + 1, args.end());
  if (command == "detect") return RunClientDetect(rest);
  if (command == "stream") return RunClientStream(rest);
  if (command == "sources") return RunClientSources(rest);
  if (command == "health") return RunClientHealth(rest);
  if (command == "--help" || command == "-h" || command == "help") {
    std::fputs(kUsage, stdout);
    return 0;
  }
  std::fprintf(stderr, "cornerpose client: unknown command '%s'\n%s", command.c_str(), kUsage);
  return 2;
}

}  // namespace cornerpose::tools
