// The daemon's status service (cornerpose.v1.RobotClientService) and gRPC
// health checking, on their own small gRPC server: thin handlers over the
// cell controller's snapshot and pick log.
#pragma once

#include <grpcpp/server.h>

#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "common/grpc_security/tls.h"
#include "cornerpose/v1/robot_client_service.grpc.pb.h"
#include "robot_client/cell/cell_controller.h"

namespace cornerpose::robot_client {

class StatusServiceImpl final : public v1::RobotClientService::CallbackService {
 public:
  explicit StatusServiceImpl(CellController* cell) : cell_(cell) {}

  grpc::ServerUnaryReactor* GetCellStatus(grpc::CallbackServerContext* context,
                                          const v1::GetCellStatusRequest* request,
                                          v1::CellStatus* response) override;
  grpc::ServerUnaryReactor* ListPicks(grpc::CallbackServerContext* context,
                                      const v1::ListPicksRequest* request,
                                      v1::ListPicksResponse* response) override;
  grpc::ServerUnaryReactor* AcknowledgeFault(grpc::CallbackServerContext* context,
                                             const v1::AcknowledgeFaultRequest* request,
                                             v1::AcknowledgeFaultResponse* response) override;

 private:
  CellController* const cell_;
};

// The proto forms of the controller's snapshot and records.
v1::CellStatus ToProto(const CellStatusSnapshot& status);
v1::PickRecord ToProto(const PickRecord& pick);

// A running status server; shuts down when destroyed.
class StatusServer {
 public:
  ~StatusServer();
  int port() const { return port_; }
  // Marks health NOT_SERVING and stops serving (idempotent).
  void Shutdown();

 private:
  friend absl::StatusOr<std::unique_ptr<StatusServer>> StartStatusServer(
      const std::string& listen_address, CellController* cell, const ServerTlsFiles& tls);
  std::unique_ptr<StatusServiceImpl> service_;
  std::unique_ptr<grpc::Server> server_;
  int port_ = 0;
};

// Listens on `listen_address` (host:port; port 0 picks one), with TLS when
// tls.cert is set (client certificates required when tls.client_ca is).
// UNAVAILABLE when the address cannot be bound; INVALID_ARGUMENT /
// NOT_FOUND for TLS files that do not go together or cannot be read.
absl::StatusOr<std::unique_ptr<StatusServer>> StartStatusServer(const std::string& listen_address,
                                                                CellController* cell,
                                                                const ServerTlsFiles& tls = {});

}  // namespace cornerpose::robot_client
