// agvslam-can-decode: decodes a candump -L log (or live `candump -L can0 | agvslam-can-decode --log -`) with a
// DBC file, checks each agvslam frame's Crc and rolling Counter, and prints physical values.
//
//   agvslam-can-decode --dbc deploy/agvslam.dbc [--log FILE|-] [--base-id 0x300] [--json] [--all]
//
// --base-id: the daemon's can.base_id when it differs from the DBC's 0x300 (ids are shifted back before lookup).
// Text: one line per known frame, "<time> <iface> <MESSAGE> Signal=value unit ... [CRC BAD]". --json: one object
// per frame {"t_ns", "interface", "id", "message", "signals": {...}, "crc_ok"} and a final {"summary": ...}.
// --all also prints frames whose id is not in the DBC. Exit status: 0 read the whole log (even with CRC errors:
// they are reported), 1 the log could not be read, 2 bad option / unreadable DBC / malformed log line.

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>

#include "agvslam/core/error.h"
#include "agvslam/drivers/can/candump_log.h"
#include "agvslam/drivers/can/dbc.h"
#include "tool_main.h"

namespace {

namespace can = agvslam::drivers::can;

struct Options {
  std::string dbc_path;
  std::string log_path = "-";
  std::string base_id = "0x300";
  bool json = false;
  bool all = false;
};

uint32_t parse_base_id(const std::string& text) {
  try {
    std::size_t used = 0;
    const auto base = static_cast<uint32_t>(std::stoul(text, &used, 0));
    if (used == text.size()) return base;
  } catch (const std::exception&) {
  }
  throw agvslam::InputError("--base-id", text, "expected a CAN id such as 0x300");
}

// Counts over the log.
struct Counts {
  std::map<std::string, long> per_message;
  long lines = 0, frames = 0, known = 0, crc_bad = 0, error_frames = 0, counter_gaps = 0;
  std::map<uint32_t, int> last_counter;  // by message id
};

void print_error_frame(const Options& o, const can::CandumpRecord& rec) {
  if (o.json) {
    std::printf(
        "%s\n",
        nlohmann::json{
            {"t_ns", rec.t_ns}, {"interface", rec.interface}, {"error_frame", true}, {"error_class", rec.frame.id}}
            .dump()
            .c_str());
  } else {
    std::printf("%.6f %s ERROR FRAME class 0x%08X\n", static_cast<double>(rec.t_ns) * 1e-9, rec.interface.c_str(),
                rec.frame.id);
  }
}

// One decoded frame: JSON, or "t interface message signal=value unit ..." with the DBC's value names.
void print_message(const Options& o, const can::CandumpRecord& rec, const can::DbcMessage& msg,
                   const std::map<std::string, double>& values, bool crc_ok) {
  if (o.json) {
    std::printf("%s\n", nlohmann::json{{"t_ns", rec.t_ns},
                                       {"interface", rec.interface},
                                       {"id", rec.frame.id},
                                       {"message", msg.name},
                                       {"signals", values},
                                       {"crc_ok", crc_ok}}
                            .dump()
                            .c_str());
    return;
  }
  std::string text;
  for (const auto& sig : msg.signals) {
    auto v = values.find(sig.name);
    if (v == values.end()) continue;
    char buf[96];
    auto named = sig.value_names.find(static_cast<int64_t>(v->second));
    if (named != sig.value_names.end()) {
      std::snprintf(buf, sizeof buf, " %s=%s", sig.name.c_str(), named->second.c_str());
    } else {
      std::snprintf(buf, sizeof buf, " %s=%.10g%s%s", sig.name.c_str(), v->second, sig.unit.empty() ? "" : " ",
                    sig.unit.c_str());
    }
    text += buf;
  }
  std::printf("%.6f %s %s%s%s\n", static_cast<double>(rec.t_ns) * 1e-9, rec.interface.c_str(), msg.name.c_str(),
              text.c_str(), crc_ok ? "" : " [CRC BAD]");
}

// A frame of a message the DBC describes: its CRC and rolling counter checked, then printed.
void decode(const Options& o, const can::CandumpRecord& rec, const can::DbcMessage& msg, Counts& n) {
  ++n.known;
  ++n.per_message[msg.name];
  const auto values = can::decode_signals(msg, rec.frame);
  bool crc_ok = true;
  if (msg.signal("Crc") != nullptr && rec.frame.len > 0) {
    crc_ok = can::frame_crc(rec.frame) == rec.frame.data[rec.frame.len - 1U];
    if (!crc_ok) ++n.crc_bad;
  }
  if (auto c = values.find("Counter"); c != values.end()) {
    const int counter = static_cast<int>(c->second);
    auto it = n.last_counter.find(msg.id);
    if (it != n.last_counter.end() && counter != ((it->second + 1) & 0xF)) ++n.counter_gaps;
    n.last_counter[msg.id] = counter;
  }
  print_message(o, rec, msg, values, crc_ok);
}

int run(const Options& o) {
  const can::Dbc dbc = can::Dbc::load(o.dbc_path);
  const uint32_t base = parse_base_id(o.base_id);
  const int64_t shift = static_cast<int64_t>(base) - 0x300;
  spdlog::info("agvslam-can-decode: dbc {} ({} messages), log {}, base id 0x{:X} (shift {:+d}), output {}", o.dbc_path,
               dbc.messages().size(), o.log_path, base, shift, o.json ? "json" : "text");

  std::ifstream file;
  std::istream* in = &std::cin;
  if (o.log_path != "-") {
    file.open(o.log_path);
    if (!file) throw agvslam::InputError(o.log_path, "file", "expected a readable candump -L log");
    in = &file;
  }
  Counts n;
  std::string line;
  int line_no = 0;
  while (std::getline(*in, line)) {
    ++line_no;
    const auto rec = can::parse_candump_line(line, o.log_path, line_no);
    if (!rec) continue;
    ++n.lines;
    if (rec->error_frame) {
      ++n.error_frames;
      print_error_frame(o, *rec);
      continue;
    }
    ++n.frames;
    const int64_t dbc_id = static_cast<int64_t>(rec->frame.id) - shift;
    const can::DbcMessage* msg = dbc_id >= 0 ? dbc.find(static_cast<uint32_t>(dbc_id), rec->frame.extended) : nullptr;
    if (msg != nullptr) {
      decode(o, *rec, *msg, n);
    } else if (o.all) {
      std::printf("%s\n", line.c_str());
    }
  }
  const nlohmann::json summary = {{"lines", n.lines},
                                  {"frames", n.frames},
                                  {"decoded", n.known},
                                  {"per_message", n.per_message},
                                  {"crc_bad", n.crc_bad},
                                  {"counter_gaps", n.counter_gaps},
                                  {"error_frames", n.error_frames}};
  if (o.json) std::printf("%s\n", nlohmann::json{{"summary", summary}}.dump().c_str());
  spdlog::info("agvslam-can-decode: {} frames, {} decoded, {} CRC errors, {} counter gaps, {} error frames", n.frames,
               n.known, n.crc_bad, n.counter_gaps, n.error_frames);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  spdlog::set_default_logger(spdlog::stderr_color_mt("agvslam-can-decode"));
  CLI::App app{"agvslam-can-decode: decode candump -L logs of the agvslam pose frames with a DBC file"};
  Options o;
  app.add_option("--dbc", o.dbc_path, "DBC file (deploy/agvslam.dbc)")->required();
  app.add_option("--log", o.log_path, "candump -L log file, - for stdin")->capture_default_str();
  app.add_option("--base-id", o.base_id, "the daemon's can.base_id")->capture_default_str();
  app.add_flag("--json", o.json, "one JSON object per frame and a summary");
  app.add_flag("--all", o.all, "also print frames the DBC does not describe");
  return agvslam::apps::parse_and_run(app, argc, argv, [&] { return run(o); });
}
