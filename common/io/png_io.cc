#include "common/io/png_io.h"

#include <png.h>

#include <bit>
#include <cerrno>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <memory>

#include "absl/strings/str_cat.h"

namespace cornerpose {
namespace {

// libpng reports errors through a callback that must not return; we record
// the message here and longjmp back to the setjmp in Decode/Encode.
struct ErrorSink {
  char message[256] = "";
};

void OnPngError(png_structp png, png_const_charp message) {
  auto* sink = static_cast<ErrorSink*>(png_get_error_ptr(png));
  if (sink != nullptr) std::snprintf(sink->message, sizeof(sink->message), "%s", message);
  png_longjmp(png, 1);
}

// Warnings (bad CRC in an ancillary chunk, ...) do not stop decoding; keep
// stderr quiet.
void OnPngWarning(png_structp, png_const_charp) {}

struct FileCloser {
  void operator()(FILE* f) const {
    if (f != nullptr) std::fclose(f);
  }
};
using FilePtr = std::unique_ptr<FILE, FileCloser>;

absl::Status OpenError(const std::string& path, const char* what, int err) {
  const std::string message = absl::StrCat(path, ": cannot open for ", what);
  if (err == ENOENT) return absl::NotFoundError(absl::StrCat(message, ": no such file"));
  return err != 0 ? absl::ErrnoToStatus(err, message) : absl::UnknownError(message);
}

enum class Want { kDepth16, kRgb8 };

struct Decoded {
  int width = 0;
  int height = 0;
  int bit_depth = 0;
  int color_type = 0;
  bool wrong_format = false;  // kDepth16 asked, the file is something else
};

// Decodes an opened PNG (signature already consumed) into *pixels. Every
// object with a destructor lives in the caller, so libpng's longjmp skips
// none. Returns false with sink->message set on a libpng error.
bool Decode(FILE* fp, Want want, Decoded* out, std::vector<uint8_t>* pixels,
            std::vector<png_bytep>* rows, ErrorSink* sink) {
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, sink, OnPngError, OnPngWarning);
  if (png == nullptr) {
    std::snprintf(sink->message, sizeof(sink->message), "out of memory");
    return false;
  }
  png_infop info = png_create_info_struct(png);
  if (info == nullptr) {
    png_destroy_read_struct(&png, nullptr, nullptr);
    std::snprintf(sink->message, sizeof(sink->message), "out of memory");
    return false;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    return false;
  }
  png_init_io(png, fp);
  png_set_sig_bytes(png, 8);
  png_set_user_limits(png, kMaxPngSide, kMaxPngSide);
  png_read_info(png, info);
  out->width = static_cast<int>(png_get_image_width(png, info));
  out->height = static_cast<int>(png_get_image_height(png, info));
  out->bit_depth = png_get_bit_depth(png, info);
  out->color_type = png_get_color_type(png, info);
  if (want == Want::kDepth16) {
    if (out->bit_depth != 16 || out->color_type != PNG_COLOR_TYPE_GRAY) {
      out->wrong_format = true;
      png_destroy_read_struct(&png, &info, nullptr);
      return true;
    }
    // PNG stores 16-bit samples big-endian.
    if constexpr (std::endian::native == std::endian::little) png_set_swap(png);
  } else {
    png_set_expand(png);
    png_set_strip_16(png);
    png_set_strip_alpha(png);
    png_set_gray_to_rgb(png);
  }
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  const size_t row_bytes = png_get_rowbytes(png, info);
  const size_t expected = static_cast<size_t>(out->width) * (want == Want::kDepth16 ? 2 : 3);
  if (row_bytes != expected) {
    std::snprintf(sink->message, sizeof(sink->message), "unexpected row size %zu (expected %zu)",
                  row_bytes, expected);
    png_destroy_read_struct(&png, &info, nullptr);
    return false;
  }
  pixels->resize(row_bytes * static_cast<size_t>(out->height));
  rows->resize(static_cast<size_t>(out->height));
  for (int v = 0; v < out->height; ++v) (*rows)[v] = pixels->data() + row_bytes * v;
  png_read_image(png, rows->data());
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return true;
}

// Opens and decodes; the shared part of ReadDepthPng and ReadRgbPng.
absl::Status ReadPng(const std::string& path, Want want, Decoded* decoded,
                     std::vector<uint8_t>* pixels) {
  FilePtr fp(std::fopen(path.c_str(), "rb"));
  if (fp == nullptr) return OpenError(path, "reading", errno);
  png_byte signature[8] = {};
  if (std::fread(signature, 1, sizeof(signature), fp.get()) != sizeof(signature) ||
      png_sig_cmp(signature, 0, sizeof(signature)) != 0) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": not a PNG file (bad signature)"));
  }
  std::vector<png_bytep> rows;
  ErrorSink sink;
  bool ok = false;
  try {
    ok = Decode(fp.get(), want, decoded, pixels, &rows, &sink);
  } catch (const std::bad_alloc&) {
    return absl::ResourceExhaustedError(absl::StrCat(path, ": out of memory decoding PNG"));
  }
  if (!ok) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": unreadable PNG: ", sink.message));
  }
  return absl::OkStatus();
}

absl::Status CheckSize(const std::string& path, int width, int height, size_t bytes,
                       size_t bytes_per_pixel) {
  if (width <= 0 || height <= 0 || width > kMaxPngSide || height > kMaxPngSide) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": image size ", width, " x ", height,
                                                   " is out of (0, ", kMaxPngSide, "]"));
  }
  if (bytes != static_cast<size_t>(width) * height * bytes_per_pixel) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": ", bytes, " bytes of pixels for a ", width, " x ", height, " image"));
  }
  return absl::OkStatus();
}

// Encodes rows into an opened file; like Decode, free of destructors.
bool Encode(FILE* fp, int width, int height, int bit_depth, int color_type, png_bytepp rows,
            ErrorSink* sink) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, sink, OnPngError, OnPngWarning);
  if (png == nullptr) {
    std::snprintf(sink->message, sizeof(sink->message), "out of memory");
    return false;
  }
  png_infop info = png_create_info_struct(png);
  if (info == nullptr) {
    png_destroy_write_struct(&png, nullptr);
    std::snprintf(sink->message, sizeof(sink->message), "out of memory");
    return false;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_init_io(png, fp);
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height),
               bit_depth, color_type, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  if (bit_depth == 16 && std::endian::native == std::endian::little) png_set_swap(png);
  png_write_image(png, rows);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

absl::Status WritePng(const std::string& path, const uint8_t* data, int width, int height,
                      int bit_depth, int color_type, size_t row_bytes) {
  std::vector<png_bytep> rows(static_cast<size_t>(height));
  for (int v = 0; v < height; ++v) rows[v] = const_cast<png_bytep>(data + row_bytes * v);
  FilePtr fp(std::fopen(path.c_str(), "wb"));
  if (fp == nullptr) return OpenError(path, "writing", errno);
  ErrorSink sink;
  if (!Encode(fp.get(), width, height, bit_depth, color_type, rows.data(), &sink)) {
    return absl::InternalError(absl::StrCat(path, ": PNG encoding failed: ", sink.message));
  }
  if (std::fclose(fp.release()) != 0) {
    const int err = errno;
    const std::string message = absl::StrCat(path, ": write failed");
    return err != 0 ? absl::ErrnoToStatus(err, message) : absl::DataLossError(message);
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<std::vector<uint16_t>> ReadDepthPng(const std::string& path, int* width,
                                                   int* height) {
  Decoded decoded;
  std::vector<uint8_t> bytes;
  if (absl::Status s = ReadPng(path, Want::kDepth16, &decoded, &bytes); !s.ok()) return s;
  if (decoded.wrong_format) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": a depth image must be a 16-bit single-channel PNG, this one has ",
                     decoded.bit_depth, "-bit samples and colour type ", decoded.color_type));
  }
  std::vector<uint16_t> depth(bytes.size() / 2);
  std::memcpy(depth.data(), bytes.data(), depth.size() * 2);
  if (width != nullptr) *width = decoded.width;
  if (height != nullptr) *height = decoded.height;
  return depth;
}

absl::Status WriteDepthPng(const std::string& path, const std::vector<uint16_t>& depth, int width,
                           int height) {
  if (absl::Status s = CheckSize(path, width, height, depth.size(), 1); !s.ok()) return s;
  return WritePng(path, reinterpret_cast<const uint8_t*>(depth.data()), width, height, 16,
                  PNG_COLOR_TYPE_GRAY, static_cast<size_t>(width) * 2);
}

absl::Status WriteRgbPng(const std::string& path, const std::vector<uint8_t>& rgb, int width,
                         int height) {
  if (absl::Status s = CheckSize(path, width, height, rgb.size(), 3); !s.ok()) return s;
  return WritePng(path, rgb.data(), width, height, 8, PNG_COLOR_TYPE_RGB,
                  static_cast<size_t>(width) * 3);
}

absl::StatusOr<std::vector<uint8_t>> ReadRgbPng(const std::string& path, int* width, int* height) {
  Decoded decoded;
  std::vector<uint8_t> rgb;
  if (absl::Status s = ReadPng(path, Want::kRgb8, &decoded, &rgb); !s.ok()) return s;
  if (width != nullptr) *width = decoded.width;
  if (height != nullptr) *height = decoded.height;
  return rgb;
}

}  // namespace cornerpose
