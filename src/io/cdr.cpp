#include "cdr.h"

#include <cstring>

#include "agvslam/core/error.h"

namespace agvslam::io::detail {

namespace {

constexpr std::size_t kEncapsulationHeaderBytes = 4;

bool host_is_big_endian() {
  const uint16_t probe = 1;
  uint8_t first = 0;
  std::memcpy(&first, &probe, 1);
  return first == 0;
}

template <typename T>
T load(const uint8_t* bytes, bool swap) {
  uint8_t copy[sizeof(T)];
  std::memcpy(copy, bytes, sizeof(T));
  if (swap) {
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(copy[i], copy[sizeof(T) - 1 - i]);
  }
  T value;
  std::memcpy(&value, copy, sizeof(T));
  return value;
}

}  // namespace

CdrReader::CdrReader(const uint8_t* data, std::size_t size, std::string source, std::string context)
    : body_(data + kEncapsulationHeaderBytes),
      size_(size >= kEncapsulationHeaderBytes ? size - kEncapsulationHeaderBytes : 0),
      source_(std::move(source)),
      context_(std::move(context)) {
  if (size < kEncapsulationHeaderBytes) {
    throw InputError(
        source_, context_,
        "expected a CDR message with a 4-byte encapsulation header, found " + std::to_string(size) + " bytes");
  }
  if (data[0] != 0 || data[1] > 1) {
    throw InputError(
        source_, context_,
        "expected plain CDR (encapsulation 0x0000 big-endian or 0x0001 little-endian), found 0x" + [&] {
          char text[8];
          std::snprintf(text, sizeof text, "%02x%02x", data[0], data[1]);
          return std::string(text);
        }());
  }
  big_endian_ = data[1] == 0;
}

void CdrReader::truncated(const char* field, std::size_t wanted) const {
  throw InputError(source_, context_ + " field '" + field + "'",
                   "expected " + std::to_string(wanted) + " more bytes at offset " + std::to_string(pos_) +
                       ", the message ends after " + std::to_string(size_) + " (truncated CDR)");
}

void CdrReader::align(std::size_t size) {
  const std::size_t rest = pos_ % size;
  if (rest != 0) pos_ += size - rest;  // may step past the end: the next take() reports it
}

const uint8_t* CdrReader::take(std::size_t size, const char* field) {
  if (pos_ > size_ || size > size_ - pos_) truncated(field, size);
  const uint8_t* at = body_ + pos_;
  pos_ += size;
  return at;
}

uint8_t CdrReader::u8(const char* field) { return *take(1, field); }

uint32_t CdrReader::u32(const char* field) {
  align(4);
  return load<uint32_t>(take(4, field), big_endian_ != host_is_big_endian());
}

int32_t CdrReader::i32(const char* field) {
  align(4);
  return load<int32_t>(take(4, field), big_endian_ != host_is_big_endian());
}

double CdrReader::f64(const char* field) {
  align(8);
  return load<double>(take(8, field), big_endian_ != host_is_big_endian());
}

std::string CdrReader::string(const char* field) {
  const uint32_t length = u32(field);
  if (length == 0) return {};  // some writers omit the NUL of an empty string
  const uint8_t* bytes = take(length, field);
  const std::size_t text_length = bytes[length - 1] == 0 ? length - 1 : length;
  return std::string(reinterpret_cast<const char*>(bytes), text_length);
}

const uint8_t* CdrReader::byte_sequence(const char* field, std::size_t& count) {
  count = u32(field);
  return take(count, field);
}

std::vector<double> CdrReader::f64_sequence(const char* field) {
  const uint32_t count = u32(field);
  if (count > size_) truncated(field, count);  // a count beyond the message: refuse before allocating
  return f64_array(field, count);
}

std::vector<double> CdrReader::f64_array(const char* field, std::size_t count) {
  std::vector<double> values(count);
  for (double& v : values) v = f64(field);
  return values;
}

int64_t read_header_stamp_ns(CdrReader& reader) {
  const int32_t sec = reader.i32("header.stamp.sec");
  const uint32_t nanosec = reader.u32("header.stamp.nanosec");
  return static_cast<int64_t>(sec) * 1'000'000'000 + static_cast<int64_t>(nanosec);
}

}  // namespace agvslam::io::detail
