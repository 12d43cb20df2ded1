// can_log_check: the VM's real-bus check (tests/drivers/can_vcan_test.sh) and a manual tool. Compares a
// candump -L log with agvslam-pose-replay --json output through the DBC.
//
//   can_log_check --dbc deploy/agvslam.dbc --log candump.log --sent sent.jsonl [--base-id 0x300]
//                 [--expect-outage]
//
// --expect-outage: the interface was taken down and up during the run; require that some cycles could not be sent
// and that sending resumed afterwards. Exit 0 pass, 1 fail (the reasons on stderr), 2 bad input.

#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>

#include "agvslam/core/error.h"
#include "can_log_checker.h"

int main(int argc, char** argv) {
  std::string dbc_path, log_path, sent_path;
  uint32_t base_id = 0x300;
  bool expect_outage = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "can_log_check: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--dbc") {
      dbc_path = next();
    } else if (a == "--log") {
      log_path = next();
    } else if (a == "--sent") {
      sent_path = next();
    } else if (a == "--base-id") {
      base_id = static_cast<uint32_t>(std::stoul(next(), nullptr, 0));
    } else if (a == "--expect-outage") {
      expect_outage = true;
    } else {
      std::fprintf(stderr, "can_log_check: unknown option %s\n", a.c_str());
      return 2;
    }
  }
  if (dbc_path.empty() || log_path.empty() || sent_path.empty()) {
    std::fprintf(stderr, "can_log_check: expected --dbc FILE --log FILE --sent FILE\n");
    return 2;
  }
  try {
    const auto dbc = agvslam::drivers::can::Dbc::load(dbc_path);
    std::vector<agvslam::drivers::can::CandumpRecord> log;
    std::ifstream lin(log_path);
    if (!lin) throw agvslam::InputError(log_path, "file", "expected a readable candump log");
    std::string line;
    int no = 0;
    while (std::getline(lin, line)) {
      if (auto r = agvslam::drivers::can::parse_candump_line(line, log_path, ++no)) log.push_back(*r);
    }
    std::vector<nlohmann::json> sent;
    std::ifstream sin(sent_path);
    if (!sin) throw agvslam::InputError(sent_path, "file", "expected agvslam-pose-replay --json output");
    while (std::getline(sin, line)) {
      if (!line.empty()) sent.push_back(nlohmann::json::parse(line));
    }
    const auto res = agvslam::test::check_can_log(dbc, sent, log, base_id);
    std::printf(
        "can_log_check: %d samples, %d cycles sent (%d whole), %d cycles in the log (%d frames), %d values "
        "checked, %d unsent, %d sent after the first unsent, %d lost at an outage\n",
        res.samples, res.expected_cycles, res.whole_cycles, res.log_cycles, res.frames, res.values_checked,
        res.unsent_samples, res.sent_after_unsent, res.lost_at_outage);
    bool ok = res.ok;
    for (const auto& f : res.failures) std::fprintf(stderr, "can_log_check: FAIL: %s\n", f.c_str());
    if (expect_outage && (res.unsent_samples == 0 || res.sent_after_unsent == 0)) {
      std::fprintf(stderr, "can_log_check: FAIL: expected an outage and a resumption (unsent %d, sent after %d)\n",
                   res.unsent_samples, res.sent_after_unsent);
      ok = false;
    }
    std::printf("can_log_check: %s\n", ok ? "PASS" : "FAIL");
    return ok ? 0 : 1;
  } catch (const agvslam::InputError& e) {
    std::fprintf(stderr, "can_log_check: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "can_log_check: %s\n", e.what());
    return 2;
  }
}
