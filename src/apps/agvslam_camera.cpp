// agvslam-camera: opens the V4L2 stereo camera the way the daemon does, grabs pairs and reports what arrived:
// rate, capture-to-dequeue latency, left/right stamp difference, dropped / unpaired / corrupt frames, losses and
// reopens. Used on a vehicle to check a camera and its configuration, and by the VM tests to check the driver.
//
//   agvslam-camera [--config params/camera.yaml [--section camera]] [--left DEV] [--right DEV] [--side-by-side]
//                  [--width W] [--height H] [--format grey|yuyv|mjpeg] [--fps F] [--tolerance-ms T]
//                  [--stall-ms S] [--backoff-ms A:B] [--frames N] [--duration-s S] [--timeout-s S] [--wait]
//                  [--ready-file FILE] [--expect-manifest FILE ...] [--expect-dataset DIR [--expect-frames A:B]
//                  [--max-mean-abs-error E]] [--min-losses N] [--save DIR]
//                  [--save-every K] [--json OUT]
//
// Stops after --frames pairs (default: the manifests' length, else 100), --duration-s, or --timeout-s without
// reaching them. --wait keeps retrying a device that is absent or not ready at start (else a failure to open
// is an error). --ready-file is written each time the camera starts streaming (its content: how many times).
// --expect-manifest (agvslam-v4l2-feed's, repeatable, concatenated) checks every frame arrived pixel-exact, in
// order, left with its own right, none missing or extra. --min-losses N requires N device losses each followed
// by a reopen. --expect-dataset compares each pair with the dataset's frame (lossy paths such as MJPEG) within
// a mean absolute error. Exit status: 0 ok, 1 a check failed or the device failed, 2 bad option or camera configuration
// (device not a capture device, format not offered, size refused).

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "agvslam/core/error.h"
#include "agvslam/core/stats.h"
#include "agvslam/drivers/v4l2/camera_config.h"
#include "agvslam/drivers/v4l2/device.h"
#include "agvslam/drivers/v4l2/pixel_convert.h"
#include "agvslam/drivers/v4l2/stereo_camera.h"
#include "agvslam/io/dataset.h"
#include "tool_main.h"

namespace {

namespace v4l2 = agvslam::drivers::v4l2;
using agvslam::InputError;

struct Options {
  std::string config, section = "camera", left, right, format, backoff, ready_file, save, json, expect_dataset,
                      expect_frames;
  double max_mean_abs_error = 2.0;
  std::vector<std::string> manifests;
  bool side_by_side = false, wait = false;
  int width = 0, height = 0, stall_ms = 0, frames = 0, min_losses = 0, save_every = 1;
  double fps = -1, tolerance_ms = -1, duration_s = 0, timeout_s = 60;
};

struct Expected {
  std::size_t index;
  uint64_t left, right;
};

std::vector<Expected> read_manifest(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "", "expected an agvslam-v4l2-feed manifest (file not readable)");
  std::vector<Expected> out;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    Expected e{};
    std::string l, r;
    if (!(s >> e.index >> l >> r))
      throw InputError(path, "line " + std::to_string(n), "expected 'index left_hash right_hash'");
    e.left = std::stoull(l, nullptr, 16);
    e.right = std::stoull(r, nullptr, 16);
    out.push_back(e);
  }
  return out;
}

nlohmann::json summary(const agvslam::Series& s) {
  return {{"median", s.median()}, {"p95", s.quantile(0.95)}, {"max", s.max()}};
}

void write_ready(const std::string& path, int count) {
  const std::string tmp = path + ".tmp";
  std::ofstream(tmp) << count << "\n";
  std::filesystem::rename(tmp, path);
}

// The camera settings: --config's section with the command line's overrides, validated.
v4l2::V4l2CameraConfig camera_config(const Options& o) {
  v4l2::V4l2CameraConfig c =
      o.config.empty() ? v4l2::V4l2CameraConfig{} : v4l2::load_v4l2_camera_config(o.config, o.section);
  if (!o.left.empty()) c.left_device = o.left;
  if (!o.right.empty()) c.right_device = o.right;
  if (o.side_by_side) c.side_by_side = true;
  if (o.width > 0) c.width = o.width;
  if (o.height > 0) c.height = o.height;
  if (!o.format.empty() && !v4l2::parse_pixel_format(o.format, c.pixel_format))
    throw InputError("--format", o.format, "expected one of grey, yuyv, mjpeg");
  if (o.fps >= 0) c.fps = o.fps;
  if (o.tolerance_ms >= 0) c.pair_tolerance_ms = o.tolerance_ms;
  if (o.stall_ms > 0) c.stall_timeout_ms = o.stall_ms;
  if (!o.backoff.empty()) {
    const auto colon = o.backoff.find(':');
    try {
      c.reopen_backoff_initial_ms = std::stoi(o.backoff.substr(0, colon));
      c.reopen_backoff_max_ms =
          colon == std::string::npos ? c.reopen_backoff_initial_ms : std::stoi(o.backoff.substr(colon + 1));
    } catch (const std::exception&) {
      throw InputError("--backoff-ms", o.backoff, "expected INITIAL:MAX in ms");
    }
  }
  c.validate(o.config.empty() ? "command line" : o.config + " + command line");
  return c;
}

// --expect-dataset: the frames a lossy path (MJPEG) must reproduce within --max-mean-abs-error grey levels,
// loaded before the camera opens so the check keeps up with the stream.
std::vector<agvslam::StereoFrame> load_reference(const Options& o) {
  std::vector<agvslam::StereoFrame> reference;
  if (o.expect_dataset.empty()) return reference;
  const auto ds = agvslam::io::open_dataset(o.expect_dataset);
  std::size_t a = 0, b = ds->size();
  if (!o.expect_frames.empty()) {
    const auto colon = o.expect_frames.find(':');
    try {
      if (colon == std::string::npos) throw std::invalid_argument("");
      a = std::stoul(o.expect_frames.substr(0, colon));
      b = std::min(b, static_cast<std::size_t>(std::stoul(o.expect_frames.substr(colon + 1))));
    } catch (const std::exception&) {
      throw InputError("--expect-frames", o.expect_frames, "expected A:B (B exclusive)");
    }
  }
  for (std::size_t i = a; i < b; ++i) reference.push_back(ds->frame(i));
  return reference;
}

// What the checks compare the stream with.
struct Expectations {
  std::vector<Expected> manifest;               // --expect-manifest, concatenated
  std::vector<agvslam::StereoFrame> reference;  // --expect-dataset
  std::size_t pairs = 100;                      // pairs to wait for
};

Expectations load_expectations(const Options& o) {
  Expectations e;
  for (const auto& m : o.manifests) {
    auto part = read_manifest(m);
    e.manifest.insert(e.manifest.end(), part.begin(), part.end());
  }
  e.reference = load_reference(o);
  e.pairs = o.frames > 0           ? static_cast<std::size_t>(o.frames)
            : !e.reference.empty() ? e.reference.size()
            : !e.manifest.empty()  ? e.manifest.size()
                                   : 100;
  return e;
}

// What arrived.
struct Capture {
  struct Got {
    uint64_t left, right;
    int64_t t_ns;
  };
  std::vector<Got> got;
  agvslam::Series latency_ms, pair_dt_ms, interval_ms;
  double last_left_mean = 0, last_right_mean = 0;
  agvslam::Series reference_error;  // mean |captured - reference| per image (grey levels)
  std::size_t reference_size_mismatch = 0;
  double elapsed_s = 0;
};

// A reference up to 15 px larger is compared on its top-left part (the feeder crops MJPEG frames to multiples
// of 16).
void compare_with_reference(const agvslam::StereoFrame& f, const agvslam::StereoFrame& ref, Capture& c) {
  const int dw = ref.left.cols - f.left.cols, dh = ref.left.rows - f.left.rows;
  if (dw < 0 || dh < 0 || dw > 15 || dh > 15 || ref.right.size() != ref.left.size() ||
      f.right.size() != f.left.size()) {
    ++c.reference_size_mismatch;
    return;
  }
  const cv::Rect roi(0, 0, f.left.cols, f.left.rows);
  c.reference_error.add(cv::norm(f.left, ref.left(roi), cv::NORM_L1) / static_cast<double>(f.left.total()));
  c.reference_error.add(cv::norm(f.right, ref.right(roi), cv::NORM_L1) / static_cast<double>(f.right.total()));
}

void save_pair(const std::string& folder, std::size_t k, const agvslam::StereoFrame& f) {
  char name[32];
  std::snprintf(name, sizeof name, "%06zu.png", k);
  cv::imwrite((std::filesystem::path(folder) / (std::string("left_") + name)).string(), f.left);
  cv::imwrite((std::filesystem::path(folder) / (std::string("right_") + name)).string(), f.right);
}

// Grabs until e.pairs arrived, --duration-s or --timeout-s; writes --ready-file each time streaming starts.
Capture capture(const Options& o, v4l2::StereoCamera& cam, const Expectations& e) {
  int streaming_starts = 0;
  auto note_state = [&, last = v4l2::CaptureStats::State::kClosed]() mutable {
    const auto s = cam.stats().state;
    if (s == v4l2::CaptureStats::State::kStreaming && last != s) {
      ++streaming_starts;
      if (!o.ready_file.empty()) write_ready(o.ready_file, streaming_starts);
    }
    last = s;
  };
  note_state();

  Capture c;
  const int64_t t_start = v4l2::monotonic_now_ns();
  const int64_t t_end = t_start + static_cast<int64_t>(o.timeout_s * 1e9);
  const int64_t t_stop = o.duration_s > 0 ? t_start + static_cast<int64_t>(o.duration_s * 1e9) : INT64_MAX;
  agvslam::StereoFrame f;
  v4l2::CaptureInfo info;
  int64_t last_status = t_start;
  while (c.got.size() < e.pairs) {
    const int64_t now = v4l2::monotonic_now_ns();
    if (now >= t_end || now >= t_stop) break;
    const auto r = cam.grab(f, 200, &info);
    note_state();
    if (r == v4l2::StereoCamera::Grab::kFrame) {
      if (!c.got.empty()) c.interval_ms.add(static_cast<double>(f.t_ns - c.got.back().t_ns) / 1e6);
      c.got.push_back({v4l2::image_hash(f.left), v4l2::image_hash(f.right), f.t_ns});
      c.latency_ms.add(static_cast<double>(info.dequeued_ns - f.t_ns) / 1e6);
      c.pair_dt_ms.add(std::abs(static_cast<double>(info.t_left_ns - info.t_right_ns)) / 1e6);
      if (c.got.size() <= e.reference.size()) compare_with_reference(f, e.reference[c.got.size() - 1], c);
      c.last_left_mean = cv::mean(f.left)[0];
      c.last_right_mean = cv::mean(f.right)[0];
      if (!o.save.empty() && (c.got.size() - 1) % static_cast<std::size_t>(std::max(1, o.save_every)) == 0) {
        save_pair(o.save, c.got.size() - 1, f);
      }
    }
    if (v4l2::monotonic_now_ns() - last_status > 2000000000LL) {
      last_status = v4l2::monotonic_now_ns();
      spdlog::info("{}", cam.stats_line());
    }
  }
  c.elapsed_s = static_cast<double>(v4l2::monotonic_now_ns() - t_start) / 1e9;
  return c;
}

// Pairs that are not the manifest's, in order (the first five named).
void check_manifest(const std::vector<Expected>& expected, const Capture& c, std::vector<std::string>& failures) {
  std::size_t mismatches = 0;
  for (std::size_t k = 0; k < std::min(c.got.size(), expected.size()); ++k) {
    if (c.got[k].left == expected[k].left && c.got[k].right == expected[k].right) continue;
    if (mismatches++ < 5) {
      std::string what = "pair " + std::to_string(k) + " is not manifest frame " + std::to_string(expected[k].index);
      for (const auto& e : expected)
        if (e.left == c.got[k].left) what += " (left is frame " + std::to_string(e.index) + ")";
      for (const auto& e : expected)
        if (e.right == c.got[k].right) what += " (right is frame " + std::to_string(e.index) + ")";
      failures.push_back(what);
    }
  }
  if (mismatches > 0) failures.push_back(std::to_string(mismatches) + " pairs differ from the manifest");
  if (c.got.size() > expected.size())
    failures.push_back(std::to_string(c.got.size() - expected.size()) + " pairs more than the manifest");
}

// Every check that failed, in words.
std::vector<std::string> check(const Options& o, const Expectations& e, const Capture& c,
                               const v4l2::CaptureStats& st) {
  std::vector<std::string> failures;
  if (c.got.size() < e.pairs)
    failures.push_back("received " + std::to_string(c.got.size()) + " of " + std::to_string(e.pairs) + " pairs");
  if (!e.manifest.empty()) check_manifest(e.manifest, c, failures);
  if (!e.reference.empty()) {
    const double worst = c.reference_error.max();
    std::printf("reference %s: mean |captured - reference| per image: median %.2f, max %.2f grey levels (limit %.2f)\n",
                o.expect_dataset.c_str(), c.reference_error.median(), worst, o.max_mean_abs_error);
    if (c.reference_size_mismatch > 0)
      failures.push_back(std::to_string(c.reference_size_mismatch) + " pairs differ in size from the reference");
    if (worst > o.max_mean_abs_error)
      failures.push_back("an image differs from its reference by " + std::to_string(worst) +
                         " grey levels on average (limit " + std::to_string(o.max_mean_abs_error) +
                         "): wrong frame or a broken conversion");
  }
  if (st.device_losses < static_cast<uint64_t>(o.min_losses))
    failures.push_back("expected at least " + std::to_string(o.min_losses) + " device losses, saw " +
                       std::to_string(st.device_losses));
  if (st.reopens < static_cast<uint64_t>(o.min_losses))
    failures.push_back("expected at least " + std::to_string(o.min_losses) + " reopens, saw " +
                       std::to_string(st.reopens));
  return failures;
}

void write_json(const std::string& path, const v4l2::V4l2CameraConfig& config, const Capture& c,
                const v4l2::CaptureStats& st, const std::vector<std::string>& failures) {
  nlohmann::json j = {{"config", config.describe()},
                      {"frames", c.got.size()},
                      {"elapsed_s", c.elapsed_s},
                      {"rate_hz", c.elapsed_s > 0 ? static_cast<double>(c.got.size()) / c.elapsed_s : 0.0},
                      {"dropped_left", st.dropped_left},
                      {"dropped_right", st.dropped_right},
                      {"unpaired_left", st.unpaired_left},
                      {"unpaired_right", st.unpaired_right},
                      {"corrupt", st.corrupt},
                      {"device_losses", st.device_losses},
                      {"reopen_attempts", st.reopen_attempts},
                      {"reopens", st.reopens},
                      {"last_error", st.last_error},
                      {"latency_ms", summary(c.latency_ms)},
                      {"pair_dt_ms", summary(c.pair_dt_ms)},
                      {"interval_ms", summary(c.interval_ms)},
                      {"last_left_mean", c.last_left_mean},
                      {"reference_mean_abs_error", summary(c.reference_error)},
                      {"last_right_mean", c.last_right_mean},
                      {"failures", failures}};
  std::ofstream(path) << j.dump(2) << "\n";
}

int run(const Options& o) {
  const v4l2::V4l2CameraConfig c = camera_config(o);
  const Expectations e = load_expectations(o);
  spdlog::info("agvslam-camera: {}", c.describe());
  spdlog::info(
      "stop after {} pairs{}, timeout {} s, {} at start, ready-file {}, manifests {} ({} frames), min losses {}, "
      "save {}",
      e.pairs, o.duration_s > 0 ? " or " + std::to_string(o.duration_s) + " s" : "", o.timeout_s,
      o.wait ? "wait for the device" : "fail if the device is not ready", o.ready_file.empty() ? "-" : o.ready_file,
      o.manifests.size(), e.manifest.size(), o.min_losses, o.save.empty() ? "-" : o.save);
  if (!o.save.empty()) std::filesystem::create_directories(o.save);

  v4l2::StereoCamera cam(c);
  cam.open(!o.wait);
  const Capture got = capture(o, cam, e);
  const auto& st = cam.stats();
  spdlog::info("{}", cam.stats_line());
  std::printf("FRAMES %zu DROPPED %llu/%llu UNPAIRED %llu/%llu CORRUPT %llu LOSSES %llu REOPENS %llu\n", got.got.size(),
              static_cast<unsigned long long>(st.dropped_left), static_cast<unsigned long long>(st.dropped_right),
              static_cast<unsigned long long>(st.unpaired_left), static_cast<unsigned long long>(st.unpaired_right),
              static_cast<unsigned long long>(st.corrupt), static_cast<unsigned long long>(st.device_losses),
              static_cast<unsigned long long>(st.reopens));
  std::printf("latency capture->dequeue ms: median %.2f p95 %.2f max %.2f; |t_left - t_right| ms max %.2f\n",
              got.latency_ms.median(), got.latency_ms.quantile(0.95), got.latency_ms.max(), got.pair_dt_ms.max());

  const std::vector<std::string> failures = check(o, e, got, st);
  if (!o.json.empty()) write_json(o.json, c, got, st, failures);
  for (const auto& fmsg : failures) spdlog::error("check failed: {}", fmsg);
  if (!failures.empty()) return 1;
  if (!e.manifest.empty()) std::printf("MANIFEST OK: %zu pairs pixel-exact and in order\n", got.got.size());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  spdlog::set_default_logger(spdlog::stderr_color_mt("camera"));
  CLI::App app{"agvslam-camera: grab stereo pairs from the V4L2 camera and report what arrived"};
  Options o;
  app.add_option("--config", o.config, "params YAML with a camera section");
  app.add_option("--section", o.section, "section of --config (default camera)");
  app.add_option("--left", o.left, "left device (side by side: the device)");
  app.add_option("--right", o.right, "right device");
  app.add_flag("--side-by-side", o.side_by_side, "one device, left|right side by side");
  app.add_option("--width", o.width, "width of one eye (px)");
  app.add_option("--height", o.height, "height (px)");
  app.add_option("--format", o.format, "grey, yuyv or mjpeg");
  app.add_option("--fps", o.fps, "frame rate to request (0: the device's)");
  app.add_option("--tolerance-ms", o.tolerance_ms, "pairing tolerance (ms)");
  app.add_option("--stall-ms", o.stall_ms, "a device silent this long is reopened (ms)");
  app.add_option("--backoff-ms", o.backoff, "reopen back-off INITIAL:MAX (ms)");
  app.add_option("--frames", o.frames, "stop after this many pairs");
  app.add_option("--duration-s", o.duration_s, "stop after this long");
  app.add_option("--timeout-s", o.timeout_s, "give up after this long");
  app.add_flag("--wait", o.wait, "keep retrying a device that is not there or not ready at start");
  app.add_option("--ready-file", o.ready_file, "written each time streaming starts");
  app.add_option("--expect-manifest", o.manifests, "agvslam-v4l2-feed manifest(s) the frames must match");
  app.add_option("--expect-dataset", o.expect_dataset,
                 "dataset whose frames (--expect-frames A:B) the pairs must match within --max-mean-abs-error");
  app.add_option("--expect-frames", o.expect_frames, "A:B, the frames of --expect-dataset that are played");
  app.add_option("--max-mean-abs-error", o.max_mean_abs_error, "grey levels, mean over an image (default 2)");
  app.add_option("--min-losses", o.min_losses, "require at least this many device losses, each reopened");
  app.add_option("--save", o.save, "write left_/right_NNNNNN.png here");
  app.add_option("--save-every", o.save_every, "save every K-th pair");
  app.add_option("--json", o.json, "write statistics as JSON");
  // A device that refuses the configuration (not a capture device, format not offered, size refused) is bad input.
  return agvslam::apps::parse_and_run(
      app, argc, argv, [&] { return run(o); },
      [](const std::exception& e) {
        const auto* device = dynamic_cast<const v4l2::V4l2Error*>(&e);
        return device != nullptr && device->configuration();
      });
}
