#include "robot_client/ur/byte_io.h"

#include <bit>
#include <cstring>

#include "absl/strings/str_cat.h"

namespace cornerpose::ur {
namespace {

void AppendBigEndian(std::string& out, uint64_t v, int n) {
  for (int i = n - 1; i >= 0; --i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}

}  // namespace

void ByteWriter::PutU8(uint8_t v) { AppendBigEndian(data_, v, 1); }
void ByteWriter::PutI8(int8_t v) { AppendBigEndian(data_, static_cast<uint8_t>(v), 1); }
void ByteWriter::PutU16(uint16_t v) { AppendBigEndian(data_, v, 2); }
void ByteWriter::PutI32(int32_t v) { AppendBigEndian(data_, static_cast<uint32_t>(v), 4); }
void ByteWriter::PutU32(uint32_t v) { AppendBigEndian(data_, v, 4); }
void ByteWriter::PutU64(uint64_t v) { AppendBigEndian(data_, v, 8); }
void ByteWriter::PutDouble(double v) { PutU64(std::bit_cast<uint64_t>(v)); }
void ByteWriter::PutFloat(float v) { PutU32(std::bit_cast<uint32_t>(v)); }
void ByteWriter::PutBytes(absl::string_view bytes) { data_.append(bytes.data(), bytes.size()); }

void ByteWriter::PatchU16(size_t offset, uint16_t v) {
  if (offset + 2 > data_.size()) return;
  data_[offset] = static_cast<char>(v >> 8);
  data_[offset + 1] = static_cast<char>(v & 0xff);
}

void ByteWriter::PatchI32(size_t offset, int32_t v) {
  if (offset + 4 > data_.size()) return;
  const auto u = static_cast<uint32_t>(v);
  for (int i = 0; i < 4; ++i) data_[offset + i] = static_cast<char>((u >> (24 - 8 * i)) & 0xff);
}

absl::Status ByteReader::Need(size_t n, absl::string_view what) const {
  if (n > remaining()) {
    return absl::OutOfRangeError(absl::StrCat(
        "truncated: ", what, " needs ", n, " bytes at offset ", pos_, ", ", remaining(), " left"));
  }
  return absl::OkStatus();
}

uint64_t ByteReader::ReadBigEndian(size_t n) {
  uint64_t v = 0;
  for (size_t i = 0; i < n; ++i) v = (v << 8) | static_cast<uint8_t>(data_[pos_ + i]);
  pos_ += n;
  return v;
}

absl::StatusOr<uint8_t> ByteReader::U8(absl::string_view what) {
  if (absl::Status s = Need(1, what); !s.ok()) return s;
  return static_cast<uint8_t>(ReadBigEndian(1));
}
absl::StatusOr<int8_t> ByteReader::I8(absl::string_view what) {
  if (absl::Status s = Need(1, what); !s.ok()) return s;
  return static_cast<int8_t>(static_cast<uint8_t>(ReadBigEndian(1)));
}
absl::StatusOr<bool> ByteReader::Bool(absl::string_view what) {
  if (absl::Status s = Need(1, what); !s.ok()) return s;
  return ReadBigEndian(1) != 0;
}
absl::StatusOr<uint16_t> ByteReader::U16(absl::string_view what) {
  if (absl::Status s = Need(2, what); !s.ok()) return s;
  return static_cast<uint16_t>(ReadBigEndian(2));
}
absl::StatusOr<int32_t> ByteReader::I32(absl::string_view what) {
  if (absl::Status s = Need(4, what); !s.ok()) return s;
  return static_cast<int32_t>(static_cast<uint32_t>(ReadBigEndian(4)));
}
absl::StatusOr<uint32_t> ByteReader::U32(absl::string_view what) {
  if (absl::Status s = Need(4, what); !s.ok()) return s;
  return static_cast<uint32_t>(ReadBigEndian(4));
}
absl::StatusOr<uint64_t> ByteReader::U64(absl::string_view what) {
  if (absl::Status s = Need(8, what); !s.ok()) return s;
  return ReadBigEndian(8);
}
absl::StatusOr<double> ByteReader::Double(absl::string_view what) {
  if (absl::Status s = Need(8, what); !s.ok()) return s;
  return std::bit_cast<double>(ReadBigEndian(8));
}
absl::StatusOr<float> ByteReader::Float(absl::string_view what) {
  if (absl::Status s = Need(4, what); !s.ok()) return s;
  return std::bit_cast<float>(static_cast<uint32_t>(ReadBigEndian(4)));
}
absl::StatusOr<absl::string_view> ByteReader::Bytes(size_t n, absl::string_view what) {
  if (absl::Status s = Need(n, what); !s.ok()) return s;
  absl::string_view out = data_.substr(pos_, n);
  pos_ += n;
  return out;
}
absl::Status ByteReader::Skip(size_t n, absl::string_view what) {
  if (absl::Status s = Need(n, what); !s.ok()) return s;
  pos_ += n;
  return absl::OkStatus();
}
absl::string_view ByteReader::Rest() {
  absl::string_view out = data_.substr(pos_);
  pos_ = data_.size();
  return out;
}

template <typename T, typename F>
T ByteReader::Sticky(F read) {
  if (!status_.ok()) return T{};
  auto v = read();
  if (!v.ok()) {
    status_ = v.status();
    return T{};
  }
  return static_cast<T>(*v);
}

uint8_t ByteReader::GetU8(absl::string_view what) {
  return Sticky<uint8_t>([&] { return U8(what); });
}
int8_t ByteReader::GetI8(absl::string_view what) {
  return Sticky<int8_t>([&] { return I8(what); });
}
bool ByteReader::GetBool(absl::string_view what) {
  return Sticky<bool>([&] { return Bool(what); });
}
uint16_t ByteReader::GetU16(absl::string_view what) {
  return Sticky<uint16_t>([&] { return U16(what); });
}
int32_t ByteReader::GetI32(absl::string_view what) {
  return Sticky<int32_t>([&] { return I32(what); });
}
uint32_t ByteReader::GetU32(absl::string_view what) {
  return Sticky<uint32_t>([&] { return U32(what); });
}
uint64_t ByteReader::GetU64(absl::string_view what) {
  return Sticky<uint64_t>([&] { return U64(what); });
}
double ByteReader::GetDouble(absl::string_view what) {
  return Sticky<double>([&] { return Double(what); });
}
float ByteReader::GetFloat(absl::string_view what) {
  return Sticky<float>([&] { return Float(what); });
}
std::string ByteReader::GetBytes(size_t n, absl::string_view what) {
  if (!status_.ok()) return {};
  absl::StatusOr<absl::string_view> v = Bytes(n, what);
  if (!v.ok()) {
    status_ = v.status();
    return {};
  }
  return std::string(*v);
}

}  // namespace cornerpose::ur
