// Big-endian (network order) byte writing and bounds-checked reading: every
// UR controller interface is big-endian.
#pragma once

#include <cstdint>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace cornerpose::ur {

class ByteWriter {
 public:
  void PutU8(uint8_t v);
  void PutI8(int8_t v);
  void PutBool(bool v) { PutU8(v ? 1 : 0); }
  void PutU16(uint16_t v);
  void PutI32(int32_t v);
  void PutU32(uint32_t v);
  void PutU64(uint64_t v);
  void PutDouble(double v);
  void PutFloat(float v);
  void PutBytes(absl::string_view bytes);

  // Overwrites 2 / 4 bytes at `offset` (< size()), e.g. a length field
  // written before the body.
  void PatchU16(size_t offset, uint16_t v);
  void PatchI32(size_t offset, int32_t v);

  const std::string& data() const { return data_; }
  std::string Take() { return std::move(data_); }
  size_t size() const { return data_.size(); }

 private:
  std::string data_;
};

// Reads from a view it does not own. A read past the end fails with
// OUT_OF_RANGE naming `what` and leaves the position unchanged.
class ByteReader {
 public:
  explicit ByteReader(absl::string_view data) : data_(data) {}

  absl::StatusOr<uint8_t> U8(absl::string_view what = "uint8");
  absl::StatusOr<int8_t> I8(absl::string_view what = "int8");
  absl::StatusOr<bool> Bool(absl::string_view what = "bool");
  absl::StatusOr<uint16_t> U16(absl::string_view what = "uint16");
  absl::StatusOr<int32_t> I32(absl::string_view what = "int32");
  absl::StatusOr<uint32_t> U32(absl::string_view what = "uint32");
  absl::StatusOr<uint64_t> U64(absl::string_view what = "uint64");
  absl::StatusOr<double> Double(absl::string_view what = "double");
  absl::StatusOr<float> Float(absl::string_view what = "float");
  absl::StatusOr<absl::string_view> Bytes(size_t n, absl::string_view what = "bytes");
  absl::Status Skip(size_t n, absl::string_view what = "bytes");
  // Everything not read yet.
  absl::string_view Rest();

  // Sticky forms for decoding a fixed layout: a short read returns 0 (empty
  // string) and records the first error, reported by status(); later reads
  // fail as well, so one check at the end covers them all.
  uint8_t GetU8(absl::string_view what = "uint8");
  int8_t GetI8(absl::string_view what = "int8");
  bool GetBool(absl::string_view what = "bool");
  uint16_t GetU16(absl::string_view what = "uint16");
  int32_t GetI32(absl::string_view what = "int32");
  uint32_t GetU32(absl::string_view what = "uint32");
  uint64_t GetU64(absl::string_view what = "uint64");
  double GetDouble(absl::string_view what = "double");
  float GetFloat(absl::string_view what = "float");
  std::string GetBytes(size_t n, absl::string_view what = "bytes");
  const absl::Status& status() const { return status_; }
  bool ok() const { return status_.ok(); }

  size_t position() const { return pos_; }
  size_t remaining() const { return data_.size() - pos_; }
  bool empty() const { return pos_ == data_.size(); }

 private:
  absl::Status Need(size_t n, absl::string_view what) const;
  uint64_t ReadBigEndian(size_t n);

  template <typename T, typename F>
  T Sticky(F read);

  absl::string_view data_;
  size_t pos_ = 0;
  absl::Status status_;
};

}  // namespace cornerpose::ur
