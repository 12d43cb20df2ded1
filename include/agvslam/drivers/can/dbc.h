#pragma once
// A reader for the subset of the Vector DBC format that describes plain (non-multiplexed) CAN and CAN FD
// messages: BO_ (messages), SG_ (signals, Intel "@1" and Motorola "@0" byte order, signed/unsigned, factor,
// offset, range, unit), VAL_ (value names) and BA_ "VFrameFormat" (CAN FD messages). Every other section is
// skipped. Used by agvslam-can-decode and by the tests that check the encoder against deploy/agvslam.dbc.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "agvslam/drivers/can/pose_frames.h"

namespace agvslam::drivers::can {

struct DbcSignal {
  std::string name;
  unsigned start_bit = 0;  // as written in the DBC (Motorola: the MSB's position)
  unsigned length = 0;
  bool little_endian = true;  // "@1" Intel, "@0" Motorola
  bool is_signed = false;     // "-" signed, "+" unsigned
  double factor = 1.0;
  double offset = 0.0;
  double minimum = 0.0;
  double maximum = 0.0;
  std::string unit;
  std::map<int64_t, std::string> value_names;  // VAL_

  // Raw integer (sign-extended when signed) from a payload; nullopt when the signal lies beyond `len` bytes.
  std::optional<int64_t> raw(const uint8_t* data, std::size_t len) const;
  double physical(int64_t raw_value) const { return static_cast<double>(raw_value) * factor + offset; }
  // Writes a physical value into a payload of at least the signal's extent: rounded to the nearest step and
  // clamped to the raw range the signal's length and sign allow (the inverse of raw() and physical()).
  void encode(double physical_value, uint8_t* data) const;
};

struct DbcMessage {
  uint32_t id = 0;  // without the extended flag
  bool extended = false;
  bool fd = false;  // BA_ "VFrameFormat" 14 (StandardCAN_FD) or 15 (ExtendedCAN_FD)
  std::string name;
  unsigned length = 0;  // bytes
  std::string transmitter;
  std::vector<DbcSignal> signals;

  const DbcSignal* signal(const std::string& signal_name) const;
};

class Dbc {
 public:
  // Throws InputError(path, "line N", "expected ...") for a syntax error in the parts it reads.
  static Dbc load(const std::string& path);
  static Dbc parse(const std::string& text, const std::string& source);

  const std::vector<DbcMessage>& messages() const { return messages_; }
  const DbcMessage* find(uint32_t id, bool extended) const;
  const DbcMessage* find(const std::string& name) const;

 private:
  std::vector<DbcMessage> messages_;
};

// Physical values of every signal of `msg` in frame `f` (signals beyond the frame's length are left out).
std::map<std::string, double> decode_signals(const DbcMessage& msg, const CanFrameBytes& f);

}  // namespace agvslam::drivers::can
