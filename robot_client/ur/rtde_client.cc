#include "robot_client/ur/rtde_client.h"

#include <algorithm>

#include "absl/strings/str_cat.h"

namespace cornerpose::ur {
namespace {

constexpr double kCb3MaxFrequency = 125.0;
constexpr double kESeriesMaxFrequency = 500.0;

// Reads frames until one of `type` arrives (controller text messages and
// data packages in between are skipped; a text message at exception level
// is returned as the error).
absl::StatusOr<RtdeFrame> ReadReply(TcpConnection& connection, RtdeFramer& framer,
                                    RtdeMessageType type, absl::Time deadline) {
  while (true) {
    absl::StatusOr<std::optional<RtdeFrame>> frame = framer.Next();
    if (!frame.ok()) return frame.status();
    if (frame->has_value()) {
      if ((*frame)->type == static_cast<uint8_t>(type)) return std::move(**frame);
      if ((*frame)->type == static_cast<uint8_t>(RtdeMessageType::kTextMessage)) {
        absl::StatusOr<RtdeTextMessage> text = ParseRtdeTextMessage((*frame)->payload);
        if (text.ok() && text->level == static_cast<uint8_t>(RtdeTextLevel::kException)) {
          return absl::FailedPreconditionError(
              absl::StrCat("RTDE controller: ", text->source, ": ", text->message));
        }
      }
      continue;
    }
    const absl::Duration left = deadline - absl::Now();
    if (left <= absl::ZeroDuration()) {
      return absl::DeadlineExceededError(
          absl::StrCat("RTDE: no reply to '", std::string(1, static_cast<char>(type)), "'"));
    }
    absl::StatusOr<std::string> bytes = connection.Read(1 << 16, left);
    if (!bytes.ok()) return bytes.status();
    framer.Append(*bytes);
  }
}

template <typename T>
const T* Get(const RtdeDataPackage& p, size_t i) {
  return i < p.values.size() ? std::get_if<T>(&p.values[i]) : nullptr;
}

Joints ToJoints(const std::array<double, 6>& v) { return v; }

UrPose ToPose(const std::array<double, 6>& v) {
  UrPose p;
  p.position << v[0], v[1], v[2];
  p.rotation << v[3], v[4], v[5];
  return p;
}

// Fills `state` from a package of the RtdeClientOutputs() recipe.
void Decode(const RtdeDataPackage& p, RtdeState& state) {
  using V6 = std::array<double, 6>;
  const std::vector<std::string>& names = RtdeClientOutputs();
  for (size_t i = 0; i < names.size(); ++i) {
    const std::string& n = names[i];
    if (n == "timestamp") {
      if (const auto* v = Get<double>(p, i)) state.timestamp = *v;
    } else if (n == "target_q") {
      if (const auto* v = Get<V6>(p, i)) state.target_q = ToJoints(*v);
    } else if (n == "actual_q") {
      if (const auto* v = Get<V6>(p, i)) state.actual_q = ToJoints(*v);
    } else if (n == "actual_qd") {
      if (const auto* v = Get<V6>(p, i)) state.actual_qd = ToJoints(*v);
    } else if (n == "actual_TCP_pose") {
      if (const auto* v = Get<V6>(p, i)) state.actual_tcp_pose = ToPose(*v);
    } else if (n == "target_TCP_pose") {
      if (const auto* v = Get<V6>(p, i)) state.target_tcp_pose = ToPose(*v);
    } else if (n == "actual_digital_output_bits") {
      if (const auto* v = Get<uint64_t>(p, i)) state.digital_outputs = *v;
    } else if (n == "actual_digital_input_bits") {
      if (const auto* v = Get<uint64_t>(p, i)) state.digital_inputs = *v;
    } else if (n == "robot_mode") {
      if (const auto* v = Get<int32_t>(p, i)) state.robot_mode = *v;
    } else if (n == "safety_mode") {
      if (const auto* v = Get<int32_t>(p, i)) state.safety_mode = *v;
    } else if (n == "safety_status_bits") {
      if (const auto* v = Get<uint32_t>(p, i)) state.safety_status_bits = *v;
    } else if (n == "robot_status_bits") {
      if (const auto* v = Get<uint32_t>(p, i)) state.robot_status_bits = *v;
    } else if (n == "runtime_state") {
      if (const auto* v = Get<uint32_t>(p, i)) state.runtime_state = *v;
    } else if (n == "speed_scaling") {
      if (const auto* v = Get<double>(p, i)) state.speed_scaling = *v;
    } else if (n == "target_speed_fraction") {
      if (const auto* v = Get<double>(p, i)) state.target_speed_fraction = *v;
    }
  }
}

}  // namespace

const std::vector<std::string>& RtdeClientOutputs() {
  static const std::vector<std::string> kOutputs = {
      "timestamp",
      "target_q",
      "actual_q",
      "actual_qd",
      "actual_TCP_pose",
      "target_TCP_pose",
      "actual_digital_output_bits",
      "actual_digital_input_bits",
      "robot_mode",
      "safety_mode",
      "safety_status_bits",
      "robot_status_bits",
      "runtime_state",
      "speed_scaling",
      "target_speed_fraction",
  };
  return kOutputs;
}

RtdeClient::RtdeClient(RtdeClientOptions options) : options_(options) {}

RtdeClient::~RtdeClient() { Stop(); }

void RtdeClient::Stop() {
  if (connection_ != nullptr) connection_->Shutdown();
  if (reader_.joinable()) reader_.join();
  std::lock_guard<std::mutex> lock(mutex_);
  connection_.reset();
  connected_ = false;
  changed_.notify_all();
}

void RtdeClient::Close() {
  Stop();
  std::lock_guard<std::mutex> lock(mutex_);
  connection_status_ = absl::UnavailableError("RTDE client closed");
}

absl::Status RtdeClient::Connect(absl::string_view host, int port, absl::Duration timeout) {
  Stop();
  const absl::Time deadline = absl::Now() + timeout;
  absl::StatusOr<TcpConnection> connection = TcpConnection::Connect(host, port, timeout);
  if (!connection.ok()) return connection.status();
  TcpConnection& c = *connection;
  RtdeFramer framer;
  auto fail = [&](absl::string_view step, const absl::Status& s) {
    return absl::Status(s.code(), absl::StrCat("RTDE ", step, ": ", s.message()));
  };

  // Protocol version 2.
  if (absl::Status s = c.WriteAll(EncodeRequestProtocolVersion()); !s.ok()) return s;
  absl::StatusOr<RtdeFrame> reply =
      ReadReply(c, framer, RtdeMessageType::kRequestProtocolVersion, deadline);
  if (!reply.ok()) return fail("protocol version", reply.status());
  absl::StatusOr<bool> accepted = ParseAccepted(reply->payload);
  if (!accepted.ok()) return fail("protocol version", accepted.status());
  if (!*accepted) return absl::FailedPreconditionError("RTDE: protocol version 2 refused");

  // Controller version, for the frequency cap.
  if (absl::Status s = c.WriteAll(EncodeGetUrcontrolVersion()); !s.ok()) return s;
  reply = ReadReply(c, framer, RtdeMessageType::kGetUrcontrolVersion, deadline);
  if (!reply.ok()) return fail("controller version", reply.status());
  absl::StatusOr<UrcontrolVersion> version = ParseUrcontrolVersion(reply->payload);
  if (!version.ok()) return fail("controller version", version.status());
  const double cap = version->major < 5 ? kCb3MaxFrequency : kESeriesMaxFrequency;

  // Output recipe.
  SetupOutputsRequest setup;
  setup.frequency = std::clamp(options_.frequency, 1.0, cap);
  setup.names = RtdeClientOutputs();
  if (absl::Status s = c.WriteAll(EncodeSetupOutputs(setup)); !s.ok()) return s;
  reply = ReadReply(c, framer, RtdeMessageType::kSetupOutputs, deadline);
  if (!reply.ok()) return fail("setup outputs", reply.status());
  absl::StatusOr<SetupReply> recipe = ParseSetupReply(reply->payload);
  if (!recipe.ok()) return fail("setup outputs", recipe.status());
  absl::StatusOr<std::vector<RtdeType>> types = RecipeTypes(*recipe, setup.names);
  if (!types.ok()) return fail("setup outputs", types.status());
  for (size_t i = 0; i < types->size(); ++i) {
    if ((*types)[i] != RtdeOutputType(setup.names[i])) {
      return absl::FailedPreconditionError(absl::StrCat(
          "RTDE setup outputs: '", setup.names[i], "' has type ", RtdeTypeName((*types)[i]),
          ", expected ", RtdeTypeName(*RtdeOutputType(setup.names[i]))));
    }
  }

  // Start.
  if (absl::Status s = c.WriteAll(EncodeStart()); !s.ok()) return s;
  reply = ReadReply(c, framer, RtdeMessageType::kStart, deadline);
  if (!reply.ok()) return fail("start", reply.status());
  accepted = ParseAccepted(reply->payload);
  if (!accepted.ok()) return fail("start", accepted.status());
  if (!*accepted) return absl::FailedPreconditionError("RTDE: start refused");

  {
    std::lock_guard<std::mutex> lock(mutex_);
    connection_ = std::make_unique<TcpConnection>(std::move(c));
    connected_ = true;
    connection_status_ = absl::OkStatus();
    latest_.reset();
    version_ = *version;
  }
  reader_ = std::thread(
      [this, conn = connection_.get(), framer = std::move(framer), id = recipe->recipe_id,
       t = std::move(*types)]() mutable { ReadLoop(conn, std::move(framer), id, std::move(t)); });
  absl::StatusOr<RtdeState> first = WaitForNewer(0, deadline - absl::Now());
  if (!first.ok()) {
    Stop();
    return fail("first data package", first.status());
  }
  return absl::OkStatus();
}

void RtdeClient::ReadLoop(TcpConnection* connection, RtdeFramer framer, uint8_t recipe_id,
                          std::vector<RtdeType> types) {
  absl::Status status;
  uint64_t sequence = 0;
  while (status.ok()) {
    // Frames already buffered during the handshake come first.
    absl::StatusOr<std::optional<RtdeFrame>> frame = framer.Next();
    if (!frame.ok()) {
      status = frame.status();
      break;
    }
    if (!frame->has_value()) {
      absl::StatusOr<std::string> bytes = connection->Read(1 << 16, options_.read_timeout);
      if (!bytes.ok()) {
        status = bytes.status();
        if (absl::IsDeadlineExceeded(status)) {
          status = absl::UnavailableError(absl::StrCat("RTDE silent for ",
                                                       absl::FormatDuration(options_.read_timeout),
                                                       " (link half-open or controller hung)"));
        }
        break;
      }
      framer.Append(*bytes);
      continue;
    }
    if ((*frame)->type != static_cast<uint8_t>(RtdeMessageType::kDataPackage)) continue;
    absl::StatusOr<RtdeDataPackage> package = ParseDataPackage((*frame)->payload, types);
    if (!package.ok() || package->recipe_id != recipe_id) continue;
    std::lock_guard<std::mutex> lock(mutex_);
    RtdeState state = latest_.value_or(RtdeState{});
    Decode(*package, state);
    state.sequence = ++sequence;
    state.received = absl::Now();
    latest_ = state;
    changed_.notify_all();
  }
  connection->Shutdown();
  std::lock_guard<std::mutex> lock(mutex_);
  connected_ = false;
  connection_status_ = status;
  changed_.notify_all();
}

bool RtdeClient::connected() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return connected_;
}

std::optional<UrcontrolVersion> RtdeClient::controller_version() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return version_;
}

absl::StatusOr<RtdeState> RtdeClient::Latest() const { return Latest(options_.max_age); }

absl::StatusOr<RtdeState> RtdeClient::Latest(absl::Duration max_age) const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!connected_) {
    return absl::UnavailableError(
        absl::StrCat("RTDE: not connected: ", connection_status_.message()));
  }
  if (!latest_) return absl::UnavailableError("RTDE: no data package yet");
  const absl::Duration age = absl::Now() - latest_->received;
  if (age > max_age) {
    return absl::DeadlineExceededError(absl::StrCat("RTDE data stale: the newest package is ",
                                                    absl::FormatDuration(age), " old (limit ",
                                                    absl::FormatDuration(max_age), ")"));
  }
  return *latest_;
}

absl::StatusOr<RtdeState> RtdeClient::WaitForNewer(uint64_t sequence,
                                                   absl::Duration timeout) const {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait_until(lock, absl::ToChronoTime(absl::Now() + timeout),
                      [&] { return !connected_ || (latest_ && latest_->sequence > sequence); });
  if (latest_ && latest_->sequence > sequence && connected_) return *latest_;
  if (!connected_) {
    return absl::UnavailableError(
        absl::StrCat("RTDE: not connected: ", connection_status_.message()));
  }
  return absl::DeadlineExceededError("RTDE: no newer data package in time");
}

}  // namespace cornerpose::ur
