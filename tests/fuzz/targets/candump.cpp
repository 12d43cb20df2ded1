// candump -L logs (agvslam-can-decode, canplayer's format): the bytes as a log, parsed line by line.
#include <string>

#include "agvslam/drivers/can/candump_log.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::size_t begin = 0;
  int line_no = 0;
  while (begin <= text.size()) {
    std::size_t end = text.find('\n', begin);
    if (end == std::string::npos) end = text.size();
    const std::string line = text.substr(begin, end - begin);
    ++line_no;
    agvslam::fuzz::expect_input_error_or_success([&] {
      const auto record = agvslam::drivers::can::parse_candump_line(line, "fuzz.log", line_no);
      if (record) agvslam::drivers::can::format_candump_line(record->frame, record->interface, record->t_ns);
    });
    begin = end + 1;
  }
  return 0;
}
