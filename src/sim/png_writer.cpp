#include "agvslam/sim/png_writer.h"

#include <libdeflate.h>

#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>

#include "agvslam/core/error.h"
#include "agvslam/sim/cpu_dispatch.h"

namespace agvslam::sim {
namespace {

void put_u32_be(uint8_t* p, uint32_t v) {
  p[0] = static_cast<uint8_t>(v >> 24);
  p[1] = static_cast<uint8_t>(v >> 16);
  p[2] = static_cast<uint8_t>(v >> 8);
  p[3] = static_cast<uint8_t>(v);
}

// Appends a chunk header (length, type) and returns its offset; finish_chunk() adds the CRC once the data is in.
std::size_t begin_chunk(std::vector<uint8_t>& out, const char type[4], uint32_t length) {
  const std::size_t at = out.size();
  out.resize(at + 8);
  put_u32_be(out.data() + at, length);
  std::memcpy(out.data() + at + 4, type, 4);
  return at;
}
void finish_chunk(std::vector<uint8_t>& out, std::size_t at) {
  const uint32_t crc = libdeflate_crc32(0, out.data() + at + 4, out.size() - at - 4);  // type and data
  const std::size_t end = out.size();
  out.resize(end + 4);
  put_u32_be(out.data() + end, crc);
}

// One row through a PNG filter: out = filter type byte, then the filtered bytes of `cur` (the row above: `prev`,
// zeros for the first row; bpp bytes per pixel).
AGVSLAM_SIM_CLONES void filter_row(PngFilter filter, const uint8_t* cur, const uint8_t* prev, std::size_t n,
                                   std::size_t bpp, uint8_t* out) {
  out[0] = static_cast<uint8_t>(filter);
  uint8_t* o = out + 1;
  switch (filter) {
    case PngFilter::kNone:
      std::memcpy(o, cur, n);
      break;
    case PngFilter::kSub:
      for (std::size_t i = 0; i < bpp && i < n; ++i) o[i] = cur[i];
      for (std::size_t i = bpp; i < n; ++i) o[i] = static_cast<uint8_t>(cur[i] - cur[i - bpp]);
      break;
    case PngFilter::kUp:
      for (std::size_t i = 0; i < n; ++i) o[i] = static_cast<uint8_t>(cur[i] - prev[i]);
      break;
    case PngFilter::kAverage:
      for (std::size_t i = 0; i < bpp && i < n; ++i) o[i] = static_cast<uint8_t>(cur[i] - (prev[i] >> 1));
      for (std::size_t i = bpp; i < n; ++i) o[i] = static_cast<uint8_t>(cur[i] - ((cur[i - bpp] + prev[i]) >> 1));
      break;
    case PngFilter::kPaeth:
      // Predictor a (left), b (up) or c (up-left), whichever is nearest to a + b - c (ties: a, then b); on the
      // first pixel a = c = 0, so it predicts b. Branch-free, so that it vectorises.
      for (std::size_t i = 0; i < bpp && i < n; ++i) o[i] = static_cast<uint8_t>(cur[i] - prev[i]);
      for (std::size_t i = bpp; i < n; ++i) {
        const int a = cur[i - bpp], b = prev[i], c = prev[i - bpp];
        const int pa = b > c ? b - c : c - b;                          // |p - a|
        const int pb = a > c ? a - c : c - a;                          // |p - b|
        const int pc = a + b > 2 * c ? a + b - 2 * c : 2 * c - a - b;  // |p - c|
        const int pred = (pa <= pb && pa <= pc) ? a : (pb <= pc ? b : c);
        o[i] = static_cast<uint8_t>(cur[i] - pred);
      }
      break;
  }
}

}  // namespace

struct PngWriter::Compressor {
  libdeflate_compressor* c;
  explicit Compressor(int level) : c(libdeflate_alloc_compressor(level)) {
    if (!c) throw std::runtime_error("libdeflate_alloc_compressor failed for level " + std::to_string(level));
  }
  ~Compressor() { libdeflate_free_compressor(c); }
  Compressor(const Compressor&) = delete;
  Compressor& operator=(const Compressor&) = delete;
};

PngWriter::PngWriter(int zlib_level) {
  if (zlib_level < 0 || zlib_level > 9) throw InputError("PngWriter", "zlib_level", "expected 0..9");
  compressor_ = std::make_unique<Compressor>(zlib_level);
}

PngWriter::~PngWriter() = default;

const std::vector<uint8_t>& PngWriter::encode(const cv::Mat& image, PngFilter filter, const std::string& what) {
  if (image.empty() || (image.type() != CV_8UC1 && image.type() != CV_16UC1))
    throw InputError(what, "image", "expected a non-empty CV_8UC1 or CV_16UC1 image");
  const bool wide = image.depth() == CV_16U;
  const std::size_t bpp = wide ? 2 : 1;
  const std::size_t row_bytes = static_cast<std::size_t>(image.cols) * bpp;
  const std::size_t rows = static_cast<std::size_t>(image.rows);

  // Filtered scanlines (PNG stores 16-bit samples big-endian).
  filtered_.resize(rows * (row_bytes + 1));
  prev_.assign(row_bytes, 0);
  cur_.resize(row_bytes);
  for (std::size_t v = 0; v < rows; ++v) {
    const uint8_t* row = image.ptr<uint8_t>(static_cast<int>(v));
    if (wide) {
      const uint16_t* samples = image.ptr<uint16_t>(static_cast<int>(v));
      for (int u = 0; u < image.cols; ++u) {
        cur_[2 * static_cast<std::size_t>(u)] = static_cast<uint8_t>(samples[u] >> 8);
        cur_[2 * static_cast<std::size_t>(u) + 1] = static_cast<uint8_t>(samples[u] & 0xffU);
      }
      row = cur_.data();
    }
    filter_row(filter, row, prev_.data(), row_bytes, bpp, filtered_.data() + v * (row_bytes + 1));
    std::memcpy(prev_.data(), row, row_bytes);
  }

  buffer_.clear();
  static constexpr uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  buffer_.insert(buffer_.end(), kSignature, kSignature + 8);
  // IHDR: width, height, bit depth, colour type 0 (grey), deflate, adaptive filtering, no interlace.
  std::size_t at = begin_chunk(buffer_, "IHDR", 13);
  buffer_.resize(buffer_.size() + 13);
  uint8_t* h = buffer_.data() + at + 8;
  put_u32_be(h, static_cast<uint32_t>(image.cols));
  put_u32_be(h + 4, static_cast<uint32_t>(image.rows));
  h[8] = wide ? 16 : 8;
  h[9] = h[10] = h[11] = h[12] = 0;
  finish_chunk(buffer_, at);
  // IDAT: the zlib stream of the filtered scanlines.
  const std::size_t bound = libdeflate_zlib_compress_bound(compressor_->c, filtered_.size());
  at = begin_chunk(buffer_, "IDAT", 0);
  buffer_.resize(at + 8 + bound);
  const std::size_t compressed =
      libdeflate_zlib_compress(compressor_->c, filtered_.data(), filtered_.size(), buffer_.data() + at + 8, bound);
  if (compressed == 0 || compressed > 0x7fffffffU)
    throw std::runtime_error(what + ": PNG encoding failed (deflate output does not fit)");
  buffer_.resize(at + 8 + compressed);
  put_u32_be(buffer_.data() + at, static_cast<uint32_t>(compressed));
  finish_chunk(buffer_, at);
  at = begin_chunk(buffer_, "IEND", 0);
  finish_chunk(buffer_, at);
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
