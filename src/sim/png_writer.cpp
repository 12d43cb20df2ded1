#include "agvslam/sim/png_writer.h"

#include <png.h>
#include <zlib.h>

#include <cstdio>
#include <cstring>
#include <memory>
#include <new>
#include <stdexcept>

#include "agvslam/core/error.h"

namespace agvslam::sim {
namespace {

// State shared with libpng's callbacks (plain data: libpng reports errors by longjmp).
struct PngContext {
  std::vector<uint8_t>* out = nullptr;
  char message[256] = {};
};

void on_error(png_structp png, png_const_charp message) {
  auto* ctx = static_cast<PngContext*>(png_get_error_ptr(png));
  std::snprintf(ctx->message, sizeof(ctx->message), "%s", message ? message : "unknown libpng error");
  png_longjmp(png, 1);
}
void on_warning(png_structp, png_const_charp) {}

void on_write(png_structp png, png_bytep data, png_size_t size) {
  auto* ctx = static_cast<PngContext*>(png_get_io_ptr(png));
  bool ok = true;
  try {
    ctx->out->insert(ctx->out->end(), data, data + size);
  } catch (const std::bad_alloc&) {
    ok = false;
  }
  if (!ok) png_error(png, "out of memory");
}
void on_flush(png_structp) {}

int libpng_filter(PngFilter f) {
  switch (f) {
    case PngFilter::kNone: return PNG_FILTER_NONE;
    case PngFilter::kSub: return PNG_FILTER_SUB;
    case PngFilter::kUp: return PNG_FILTER_UP;
    case PngFilter::kAverage: return PNG_FILTER_AVG;
    case PngFilter::kPaeth: return PNG_FILTER_PAETH;
  }
  return PNG_FILTER_NONE;
}

// Encodes grey rows into ctx.out. Returns false with ctx.message set when libpng fails. (Only trivially
// destructible locals: libpng's errors longjmp back here.)
bool encode_grey(PngContext& ctx, int width, int height, int bit_depth, const uint8_t* const* rows, int filter,
                 int zlib_level) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &ctx, on_error, on_warning);
  if (!png) {
    std::snprintf(ctx.message, sizeof(ctx.message), "png_create_write_struct failed");
    return false;
  }
  png_infop info = png_create_info_struct(png);
  if (!info) {
    png_destroy_write_struct(&png, nullptr);
    std::snprintf(ctx.message, sizeof(ctx.message), "png_create_info_struct failed");
    return false;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_set_write_fn(png, &ctx, on_write, on_flush);
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), bit_depth,
               PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_filter(png, PNG_FILTER_TYPE_BASE, filter);
  png_set_compression_level(png, zlib_level);
  png_set_compression_strategy(png, Z_RLE);
  png_write_info(png, info);
  if (bit_depth == 16) {
    const uint16_t probe = 1;
    uint8_t first_byte;
    std::memcpy(&first_byte, &probe, 1);
    if (first_byte == 1) png_set_swap(png);  // PNG stores 16-bit samples big-endian
  }
  png_write_image(png, const_cast<png_bytepp>(rows));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

}  // namespace

PngWriter::PngWriter(int zlib_level) : zlib_level_(zlib_level) {
  if (zlib_level < 0 || zlib_level > 9) throw InputError("PngWriter", "zlib_level", "expected 0..9");
}

const std::vector<uint8_t>& PngWriter::encode(const cv::Mat& image, PngFilter filter, const std::string& what) {
  if (image.empty() || (image.type() != CV_8UC1 && image.type() != CV_16UC1))
    throw InputError(what, "image", "expected a non-empty CV_8UC1 or CV_16UC1 image");
  rows_.resize(static_cast<std::size_t>(image.rows));
  for (int v = 0; v < image.rows; ++v) rows_[static_cast<std::size_t>(v)] = image.ptr<uint8_t>(v);
  buffer_.clear();
  buffer_.reserve(image.total() * image.elemSize() + static_cast<std::size_t>(image.rows) + 4096);
  PngContext ctx;
  ctx.out = &buffer_;
  if (!encode_grey(ctx, image.cols, image.rows, image.depth() == CV_16U ? 16 : 8, rows_.data(), libpng_filter(filter),
                   zlib_level_))
    throw std::runtime_error(what + ": PNG encoding failed: " + ctx.message);
  return buffer_;
}

void PngWriter::write(const std::string& path, const cv::Mat& image, PngFilter filter, const std::string& option) {
  encode(image, filter, path);
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "wb"), &std::fclose);
  if (!file) throw InputError(option, path, "could not open the image for writing");
  const bool written = std::fwrite(buffer_.data(), 1, buffer_.size(), file.get()) == buffer_.size();
  const bool closed = std::fclose(file.release()) == 0;
  if (!written || !closed) throw InputError(option, path, "could not write the image (disk full or not writable?)");
}

}  // namespace agvslam::sim
