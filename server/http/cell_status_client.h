// /api/cell: the robot-cell daemon's status (RobotClientService
// GetCellStatus and ListPicks) fetched over gRPC and written as the JSON of
// web/README.md.
#pragma once

#include <grpcpp/channel.h>

#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "common/grpc_security/tls.h"
#include "cornerpose/v1/robot_client_service.grpc.pb.h"

namespace cornerpose::server {

class CellStatusClient {
 public:
  // `address` host:port of the daemon's status service, over TLS when `tls`
  // is set (as the daemon serves it), else plaintext. INVALID_ARGUMENT /
  // NOT_FOUND (naming the file) for TLS files that do not go together or
  // cannot be read.
  static absl::StatusOr<std::unique_ptr<CellStatusClient>> Create(std::string address,
                                                                  const ClientTlsFiles& tls);

  // {"configured": true, "reachable": ..., ...}; each call asks the daemon
  // (one second deadline), so a stopped daemon shows as unreachable.
  std::string StatusJson();

 private:
  CellStatusClient(std::string address, std::unique_ptr<v1::RobotClientService::Stub> stub)
      : address_(std::move(address)), stub_(std::move(stub)) {}

  const std::string address_;
  std::unique_ptr<v1::RobotClientService::Stub> stub_;
};

}  // namespace cornerpose::server
