#pragma once
// Private to the io module: a reader of CDR (XCDR1) serialised ROS 2 messages, as rosbag2 stores them.
//
// A message starts with a 4-byte encapsulation header: 0x00 0x00 = big-endian CDR, 0x00 0x01 = little-endian
// CDR, then two option bytes. Primitives are aligned to their own size (8 at most) relative to the end of that
// header. A string is a uint32 length that counts its terminating NUL, then the bytes; a sequence is a uint32
// element count, then the elements; a fixed array has no count.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace agvslam::io::detail {

class CdrReader {
 public:
  // data must outlive the reader. source / context name the message in errors ("bag.db3", "topic /cam/left
  // message 12"). Throws InputError for a header that is not plain CDR.
  CdrReader(const uint8_t* data, std::size_t size, std::string source, std::string context);

  // Each read names the field it is reading (`field`, e.g. "height") in the InputError thrown when the message
  // ends before it.
  uint8_t u8(const char* field);
  uint32_t u32(const char* field);
  int32_t i32(const char* field);
  double f64(const char* field);
  std::string string(const char* field);
  // A uint8[] sequence: returns where its bytes start in the message and how many there are.
  const uint8_t* byte_sequence(const char* field, std::size_t& count);
  // A float64[] sequence (count read from the message) or array (count given).
  std::vector<double> f64_sequence(const char* field);
  std::vector<double> f64_array(const char* field, std::size_t count);

  bool big_endian() const { return big_endian_; }

 private:
  void align(std::size_t size);
  const uint8_t* take(std::size_t size, const char* field);
  [[noreturn]] void truncated(const char* field, std::size_t wanted) const;

  const uint8_t* body_;  // first byte after the encapsulation header
  std::size_t size_;     // bytes after the encapsulation header
  std::size_t pos_ = 0;  // relative to body_
  bool big_endian_ = false;
  std::string source_, context_;
};

// The header stamp of a message whose first field is std_msgs/Header (sec, nanosec), in nanoseconds.
int64_t read_header_stamp_ns(CdrReader& reader);

}  // namespace agvslam::io::detail
