#include "server/http/cell_status_client.h"

#include <grpcpp/create_channel.h>
#include <grpcpp/security/credentials.h>

#include <chrono>
#include <nlohmann/json.hpp>
#include <utility>

#include "absl/strings/str_cat.h"

namespace cornerpose::server {
namespace {

using nlohmann::json;

constexpr auto kDeadline = std::chrono::seconds(1);
// The page shows the newest picks; the daemon keeps 100.
constexpr int kMaxPicks = 20;

// "PICK_OUTCOME_COMPLETED" -> "COMPLETED".
std::string Short(const std::string& name, const std::string& prefix) {
  return name.rfind(prefix, 0) == 0 ? name.substr(prefix.size()) : name;
}

}  // namespace

absl::StatusOr<std::unique_ptr<CellStatusClient>> CellStatusClient::Create(
    std::string address, const ClientTlsFiles& tls) {
  grpc::ChannelArguments args;
  absl::StatusOr<std::shared_ptr<grpc::ChannelCredentials>> credentials =
      MakeChannelCredentials(tls, &args);
  if (!credentials.ok()) {
    return absl::Status(credentials.status().code(),
                        absl::StrCat("cell status TLS: ", credentials.status().message()));
  }
  auto stub =
      v1::RobotClientService::NewStub(grpc::CreateCustomChannel(address, *credentials, args));
  return std::unique_ptr<CellStatusClient>(
      new CellStatusClient(std::move(address), std::move(stub)));
}

std::string CellStatusClient::StatusJson() {
  json out = {{"configured", true}, {"address", address_}};
  v1::CellStatus status;
  {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + kDeadline);
    const grpc::Status s = stub_->GetCellStatus(&context, v1::GetCellStatusRequest(), &status);
    if (!s.ok()) {
      out["reachable"] = false;
      out["error"] = s.error_message();
      return out.dump();
    }
  }
  out["reachable"] = true;
  out["state"] = Short(v1::CellState_Name(status.state()), "CELL_STATE_");
  out["stop_reason"] = status.stop_reason();
  out["picks_done"] = status.picks_done();
  out["picks_failed"] = status.picks_failed();
  out["next_slot"] = status.next_slot();
  out["num_slots"] = status.num_slots();
  out["perception_connected"] = status.perception_connected();
  out["robot_connected"] = status.robot_connected();
  out["dry_run"] = status.dry_run();
  json picks = json::array();
  v1::ListPicksRequest request;
  request.set_max_picks(kMaxPicks);
  v1::ListPicksResponse response;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + kDeadline);
  if (const grpc::Status s = stub_->ListPicks(&context, request, &response); !s.ok()) {
    out["picks_error"] = s.error_message();
  }
  for (const v1::PickRecord& p : response.picks()) {
    const v1::Vector3& t = p.base_pose_box().position();
    picks.push_back({{"pick_id", p.pick_id()},
                     {"outcome", Short(v1::PickOutcome_Name(p.outcome()), "PICK_OUTCOME_")},
                     {"source", p.source()},
                     {"frame_id", p.frame_id()},
                     {"score", p.score()},
                     {"box_position", json::array({t.x(), t.y(), t.z()})},
                     {"slot", p.slot()},
                     {"program_s", p.program_s()},
                     {"detail", p.detail()},
                     {"start_time_unix_ms", static_cast<double>(p.start_time_unix_nanos()) / 1e6}});
  }
  out["picks"] = picks;
  return out.dump();
}

}  // namespace cornerpose::server
