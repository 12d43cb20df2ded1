#pragma once
// Checks a candump -L log of the CAN pose output against what agvslam-pose-replay --json says it sent, using
// only the DBC's signal definitions (deploy/agvslam.dbc) and the documented Crc/Counter rules: every pose the
// driver handed to the socket must be in the log, in order, with every signal within half a resolution step of
// the sample's SI value. Used by the host tests (frames encoded here, log written here) and by the real-bus test
// in the VM (tests/drivers/can_vcan_test.sh, candump writes the log).

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "agvslam/drivers/can/candump_log.h"
#include "agvslam/drivers/can/dbc.h"

namespace agvslam::test {

struct CanCheckResult {
  bool ok = false;
  std::vector<std::string> failures;  // first few problems, human-readable
  int samples = 0;                    // sent.jsonl samples
  int expected_cycles = 0;            // samples with at least one frame accepted by the socket
  int whole_cycles = 0;               // samples with every frame accepted
  int log_cycles = 0;                 // cycles found in the log
  int frames = 0;                     // agvslam frames in the log
  int values_checked = 0;
  int unsent_samples = 0;     // due samples the driver could not send (interface down)
  int sent_after_unsent = 0;  // whole cycles sent after the first unsent one (resumed)
  int lost_at_outage = 0;     // cycles sent just before an outage that did not reach the bus (allowed)
};

// `sent`: the JSON lines of agvslam-pose-replay --json (lines without "i" are ignored). `log`: candump -L lines.
CanCheckResult check_can_log(const drivers::can::Dbc& dbc, const std::vector<nlohmann::json>& sent,
                             const std::vector<drivers::can::CandumpRecord>& log, uint32_t base_id = 0x300);

}  // namespace agvslam::test
