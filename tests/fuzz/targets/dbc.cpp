// DBC files (deploy/agvslam.dbc or a vehicle's own, named by can_odometry.dbc), then every signal of every message
// decoded from an all-ones frame of the message's length.
#include <algorithm>
#include <string>

#include "agvslam/drivers/can/dbc.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  using namespace agvslam::drivers::can;
  const std::string text(reinterpret_cast<const char*>(data), size);
  agvslam::fuzz::expect_input_error_or_success([&] {
    const Dbc dbc = Dbc::parse(text, "fuzz.dbc");
    for (const DbcMessage& m : dbc.messages()) {
      CanFrameBytes frame;
      frame.id = m.id;
      frame.extended = m.extended;
      frame.fd = m.fd;
      frame.len = static_cast<uint8_t>(std::min<unsigned>(m.length, 64));
      frame.data.fill(0xFF);
      decode_signals(m, frame);
      dbc.find(m.id, m.extended);
      dbc.find(m.name);
    }
  });
  return 0;
}
