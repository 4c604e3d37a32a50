// /api/cell: the robot-cell daemon's status (RobotClientService
// GetCellStatus and ListPicks) fetched over gRPC and written as the JSON of
// web/README.md.
#pragma once

#include <grpcpp/channel.h>

#include <memory>
#include <string>

#include "cornerpose/v1/robot_client_service.grpc.pb.h"

namespace cornerpose::server {

class CellStatusClient {
 public:
  // `address` host:port of the daemon's status service (insecure channel,
  // as the daemon serves it).
  explicit CellStatusClient(std::string address);

  // {"configured": true, "reachable": ..., ...}; each call asks the daemon
  // (one second deadline), so a stopped daemon shows as unreachable.
  std::string StatusJson();

 private:
  const std::string address_;
  std::unique_ptr<v1::RobotClientService::Stub> stub_;
};

}  // namespace cornerpose::server
