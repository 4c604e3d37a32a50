#include "robot_client/cell/status_service.h"

#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>

#include <chrono>

#include "absl/strings/str_cat.h"
#include "common/grpc_security/reflection.h"

namespace cornerpose::robot_client {
namespace {

v1::Pose PoseToProto(const Eigen::Isometry3d& parent_T_child) {
  v1::Pose out;
  const Eigen::Vector3d t = parent_T_child.translation();
  const Eigen::Quaterniond q(parent_T_child.rotation());
  out.mutable_position()->set_x(t.x());
  out.mutable_position()->set_y(t.y());
  out.mutable_position()->set_z(t.z());
  out.mutable_orientation()->set_w(q.w());
  out.mutable_orientation()->set_x(q.x());
  out.mutable_orientation()->set_y(q.y());
  out.mutable_orientation()->set_z(q.z());
  return out;
}

v1::CellState StateToProto(CellState state) {
  switch (state) {
    case CellState::kStarting:
      return v1::CELL_STATE_STARTING;
    case CellState::kIdle:
      return v1::CELL_STATE_IDLE;
    case CellState::kPicking:
      return v1::CELL_STATE_PICKING;
    case CellState::kStopped:
      return v1::CELL_STATE_STOPPED;
    case CellState::kFinished:
      return v1::CELL_STATE_FINISHED;
  }
  return v1::CELL_STATE_UNSPECIFIED;
}

v1::PickOutcome OutcomeToProto(PickOutcome outcome) {
  switch (outcome) {
    case PickOutcome::kCompleted:
      return v1::PICK_OUTCOME_COMPLETED;
    case PickOutcome::kProtectiveStop:
      return v1::PICK_OUTCOME_PROTECTIVE_STOP;
    case PickOutcome::kRuntimeException:
      return v1::PICK_OUTCOME_RUNTIME_EXCEPTION;
    case PickOutcome::kConnectionLost:
      return v1::PICK_OUTCOME_CONNECTION_LOST;
    case PickOutcome::kDryRun:
      return v1::PICK_OUTCOME_DRY_RUN;
    case PickOutcome::kTimeout:
      return v1::PICK_OUTCOME_TIMEOUT;
    case PickOutcome::kUnknown:
      return v1::PICK_OUTCOME_UNKNOWN;
  }
  return v1::PICK_OUTCOME_UNSPECIFIED;
}

}  // namespace

v1::CellStatus ToProto(const CellStatusSnapshot& status) {
  v1::CellStatus out;
  out.set_state(StateToProto(status.state));
  out.set_stop_reason(status.stop_reason);
  out.set_picks_done(static_cast<uint32_t>(status.picks_done));
  out.set_picks_failed(static_cast<uint32_t>(status.picks_failed));
  out.set_next_slot(static_cast<uint32_t>(status.next_slot));
  out.set_num_slots(static_cast<uint32_t>(status.num_slots));
  out.set_perception_connected(status.perception_connected);
  out.set_robot_connected(status.robot_connected);
  out.set_dry_run(status.dry_run);
  out.set_awaiting_acknowledgement(status.awaiting_acknowledgement);
  out.set_unknown_pick_id(status.unknown_pick_id);
  out.set_last_acknowledgement(status.last_acknowledgement);
  return out;
}

v1::PickRecord ToProto(const PickRecord& pick) {
  v1::PickRecord out;
  out.set_pick_id(pick.pick_id);
  out.set_program_name(pick.program_name);
  out.set_source(pick.source);
  out.set_frame_id(pick.frame_id);
  out.set_capture_time_unix_nanos(absl::ToUnixNanos(pick.capture_time));
  *out.mutable_base_pose_box() = PoseToProto(pick.plan.box.base_T_box);
  out.set_score(pick.score);
  *out.mutable_initial() = PoseToProto(pick.plan.initial);
  *out.mutable_approach() = PoseToProto(pick.plan.approach);
  *out.mutable_grasp() = PoseToProto(pick.plan.grasp);
  *out.mutable_retrieve() = PoseToProto(pick.plan.retrieve);
  *out.mutable_place() = PoseToProto(pick.plan.place);
  out.set_slot(static_cast<uint32_t>(pick.plan.slot));
  out.set_outcome(OutcomeToProto(pick.outcome));
  out.set_detail(pick.detail);
  out.set_plan_ms(pick.plan_ms);
  out.set_program_s(pick.program_s);
  out.set_start_time_unix_nanos(absl::ToUnixNanos(pick.start_time));
  return out;
}

grpc::ServerUnaryReactor* StatusServiceImpl::GetCellStatus(
    grpc::CallbackServerContext* context, const v1::GetCellStatusRequest* /*request*/,
    v1::CellStatus* response) {
  *response = ToProto(cell_->Status());
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  reactor->Finish(grpc::Status::OK);
  return reactor;
}

grpc::ServerUnaryReactor* StatusServiceImpl::ListPicks(grpc::CallbackServerContext* context,
                                                       const v1::ListPicksRequest* request,
                                                       v1::ListPicksResponse* response) {
  for (const PickRecord& pick : cell_->Picks(request->max_picks())) {
    *response->add_picks() = ToProto(pick);
  }
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  reactor->Finish(grpc::Status::OK);
  return reactor;
}

grpc::ServerUnaryReactor* StatusServiceImpl::AcknowledgeFault(
    grpc::CallbackServerContext* context, const v1::AcknowledgeFaultRequest* request,
    v1::AcknowledgeFaultResponse* response) {
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  absl::StatusOr<std::string> cleared =
      cell_->AcknowledgeFault(request->operator_(), request->note(), request->unknown_pick_placed());
  if (!cleared.ok()) {
    reactor->Finish(grpc::Status(static_cast<grpc::StatusCode>(cleared.status().code()),
                                 std::string(cleared.status().message())));
    return reactor;
  }
  response->set_cleared(*cleared);
  reactor->Finish(grpc::Status::OK);
  return reactor;
}

StatusServer::~StatusServer() { Shutdown(); }

void StatusServer::Shutdown() {
  if (!server_) return;
  if (grpc::HealthCheckServiceInterface* health = server_->GetHealthCheckService()) {
    health->Shutdown();
  }
  server_->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(2));
  server_.reset();
}

absl::StatusOr<std::unique_ptr<StatusServer>> StartStatusServer(const std::string& listen_address,
                                                                CellController* cell,
                                                                const ServerTlsFiles& tls) {
  absl::StatusOr<std::shared_ptr<grpc::ServerCredentials>> credentials = MakeServerCredentials(tls);
  if (!credentials.ok()) return credentials.status();
  grpc::EnableDefaultHealthCheckService(true);
  auto out = std::unique_ptr<StatusServer>(new StatusServer());
  out->service_ = std::make_unique<StatusServiceImpl>(cell);
  grpc::ServerBuilder builder;
  // Reflection only where nobody else can reach it in plaintext.
  ConfigureReflection(builder, IsLoopbackAddress(listen_address) || tls.enabled());
  builder.AddListeningPort(listen_address, *credentials, &out->port_);
  builder.RegisterService(out->service_.get());
  out->server_ = builder.BuildAndStart();
  if (!out->server_ || out->port_ == 0) {
    return absl::UnavailableError(
        absl::StrCat("cannot listen on ", listen_address, " for the status service"));
  }
  return out;
}

}  // namespace cornerpose::robot_client
