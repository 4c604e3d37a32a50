#include "server/service/status_mapping.h"

#include <gtest/gtest.h>

namespace cornerpose::server {
namespace {

TEST(StatusMappingTest, OkIsOk) { EXPECT_TRUE(ToGrpcStatus(absl::OkStatus()).ok()); }

TEST(StatusMappingTest, CodeForCodeWithMessage) {
  const std::pair<absl::Status, grpc::StatusCode> cases[] = {
      {absl::InvalidArgumentError("bad cloud"), grpc::StatusCode::INVALID_ARGUMENT},
      {absl::NotFoundError("no source"), grpc::StatusCode::NOT_FOUND},
      {absl::UnavailableError("camera gone"), grpc::StatusCode::UNAVAILABLE},
      {absl::DeadlineExceededError("late"), grpc::StatusCode::DEADLINE_EXCEEDED},
      {absl::CancelledError("gone"), grpc::StatusCode::CANCELLED},
      {absl::ResourceExhaustedError("big"), grpc::StatusCode::RESOURCE_EXHAUSTED},
      {absl::InternalError("bug"), grpc::StatusCode::INTERNAL},
      {absl::UnauthenticatedError("who"), grpc::StatusCode::UNAUTHENTICATED},
  };
  for (const auto& [in, code] : cases) {
    const grpc::Status out = ToGrpcStatus(in);
    EXPECT_EQ(out.error_code(), code) << in;
    EXPECT_EQ(out.error_message(), std::string(in.message()));
  }
}

TEST(StatusMappingTest, CodeOutsideTheStandardSetIsUnknown) {
  const grpc::Status out = ToGrpcStatus(absl::Status(static_cast<absl::StatusCode>(99), "odd"));
  EXPECT_EQ(out.error_code(), grpc::StatusCode::UNKNOWN);
  EXPECT_EQ(out.error_message(), "odd");
}

}  // namespace
}  // namespace cornerpose::server
