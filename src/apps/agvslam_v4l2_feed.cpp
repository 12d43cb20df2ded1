// agvslam-v4l2-feed: plays a stereo sequence into V4L2 output devices (v4l2loopback) as GREY frames, so the
// camera driver and the daemon can be tested with real images through a real kernel V4L2 path.
//
//   agvslam-v4l2-feed --dataset DIR --left /dev/videoL --right /dev/videoR [--rate-hz R] [--frames A:B]
//                     [--manifest FILE] [--wait-file FILE] [--wait-timeout-s S] [--start-delay-s S]
//                     [--stamp queue|write] [--format grey|mjpeg] [--jpeg-quality Q] [--json OUT]
//   agvslam-v4l2-feed --dataset DIR --side-by-side --left /dev/videoN ...     one device, left|right side by side
//   agvslam-v4l2-feed --dataset DIR --frames A:B --manifest FILE --dry-run    only write the manifest
//
// The dataset is any folder agvslam's readers take (KITTI layout, EuRoC ASL: rectified on load). All frames are
// loaded first; then the devices are opened and announced (readers can open them), the tool waits for
// --wait-file (a reader says it is streaming) and writes one pair per period on an absolute schedule.
// --manifest writes "index left_hash right_hash" per frame (64-bit FNV-1a of the grey pixels, hex) before
// playing, for agvslam-camera --expect-manifest. Exit status: 0 done, 1 device or timing failure, 2 bad input.

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <thread>

#include "agvslam/core/error.h"
#include "agvslam/core/stats.h"
#include "agvslam/drivers/v4l2/device.h"
#include "agvslam/drivers/v4l2/pixel_convert.h"
#include "agvslam/drivers/v4l2/stereo_camera.h"
#include "agvslam/io/dataset.h"
#include "tool_main.h"

namespace {

namespace v4l2 = agvslam::drivers::v4l2;
using agvslam::InputError;

struct Options {
  std::string dataset, left, right, frames, manifest, wait_file, json, stamp = "queue", format = "grey";
  int jpeg_quality = 90;
  bool side_by_side = false, dry_run = false;
  double rate_hz = 0, wait_timeout_s = 60, start_delay_s = 0;
};

void parse_range(const std::string& s, std::size_t n, std::size_t& a, std::size_t& b) {
  a = 0;
  b = n;
  if (s.empty()) return;
  const auto colon = s.find(':');
  try {
    if (colon == std::string::npos) throw std::invalid_argument("");
    if (colon > 0) a = std::stoul(s.substr(0, colon));
    if (colon + 1 < s.size()) b = std::min(n, static_cast<std::size_t>(std::stoul(s.substr(colon + 1))));
  } catch (const std::exception&) {
    throw InputError("--frames", s, "expected A:B (frame indices, B exclusive)");
  }
  if (a >= b) throw InputError("--frames", s, "expected A < B <= " + std::to_string(n));
}

std::string hex(uint64_t h) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

// Options that need no file: InputError naming the option otherwise.
void check_options(const Options& o) {
  if (!o.dry_run && o.left.empty()) throw InputError("--left", "", "expected an output device");
  if (!o.dry_run && !o.side_by_side && o.right.empty())
    throw InputError("--right", "", "expected an output device (or --side-by-side)");
  if (o.rate_hz < 0) throw InputError("--rate-hz", "", "expected a rate > 0");
}

// The frames a..b-1 of the dataset, continuous; for MJPEG cropped to multiples of 16.
struct Frames {
  std::vector<cv::Mat> left, right;
};

Frames load_frames(const Options& o, const agvslam::io::StereoDataset& ds, std::size_t a, std::size_t b) {
  Frames f;
  for (std::size_t i = a; i < b; ++i) {
    agvslam::StereoFrame frame = ds.frame(i);
    f.left.push_back(frame.left.isContinuous() ? frame.left : frame.left.clone());
    f.right.push_back(frame.right.isContinuous() ? frame.right : frame.right.clone());
  }
  if (o.format == "mjpeg") {
    // libv4lconvert decodes JPEGs whose size is a multiple of the 16x16 block (as every UVC camera's is): crop.
    const cv::Rect roi(0, 0, f.left.front().cols & ~15, f.left.front().rows & ~15);
    if (roi.width != f.left.front().cols || roi.height != f.left.front().rows)
      spdlog::info("MJPEG: frames cropped to their top-left {}x{} (multiples of 16)", roi.width, roi.height);
    for (auto& m : f.left) m = m(roi).clone();
    for (auto& m : f.right) m = m(roi).clone();
  }
  return f;
}

// "index left_hash right_hash" per frame, written atomically.
void write_manifest(const std::string& path, const std::string& dataset_root, const Frames& f, std::size_t a) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream m(tmp);
    if (!m) throw InputError(path, "", "expected a writable file");
    m << "# agvslam-v4l2-feed manifest: index left_fnv1a64 right_fnv1a64; dataset " << dataset_root << " "
      << f.left.front().cols << "x" << f.left.front().rows << "\n";
    for (std::size_t k = 0; k < f.left.size(); ++k)
      m << (a + k) << " " << hex(v4l2::image_hash(f.left[k])) << " " << hex(v4l2::image_hash(f.right[k])) << "\n";
  }
  std::filesystem::rename(tmp, path);
}

// MJPEG: every frame encoded once before playing (3 channels of the grey value, OpenCV's 4:2:0 sampling); side by
// side, the pairs go into `left` alone.
struct Jpegs {
  std::vector<std::vector<uint8_t>> left, right;
};

Jpegs encode_jpegs(const Options& o, const Frames& f) {
  Jpegs out;
  cv::Mat bgr, both;
  auto encode = [&](const cv::Mat& grey, std::vector<std::vector<uint8_t>>& to) {
    cv::cvtColor(grey, bgr, cv::COLOR_GRAY2BGR);
    to.emplace_back();
    cv::imencode(".jpg", bgr, to.back(), {cv::IMWRITE_JPEG_QUALITY, o.jpeg_quality});
  };
  for (std::size_t k = 0; k < f.left.size(); ++k) {
    if (o.side_by_side) {
      cv::hconcat(f.left[k], f.right[k], both);
      encode(both, out.left);
    } else {
      encode(f.left[k], out.left);
      encode(f.right[k], out.right);
    }
  }
  return out;
}

// The output devices, opened and announced (readers can open them); side by side only `left`.
struct Outputs {
  std::unique_ptr<v4l2::V4l2Output> left, right;
};

Outputs open_outputs(const Options& o, int width, int height) {
  const auto pf = o.format == "mjpeg" ? v4l2::PixelFormat::kMjpeg : v4l2::PixelFormat::kGrey;
  const auto mode = o.stamp == "write" ? v4l2::V4l2Output::Mode::kWrite : v4l2::V4l2Output::Mode::kQueue;
  Outputs out;
  if (o.side_by_side) {
    out.left = std::make_unique<v4l2::V4l2Output>(o.left, 2 * width, height, mode, pf);
  } else {
    out.left = std::make_unique<v4l2::V4l2Output>(o.left, width, height, mode, pf);
    out.right = std::make_unique<v4l2::V4l2Output>(o.right, width, height, mode, pf);
  }
  out.left->announce();
  if (out.right) out.right->announce();
  spdlog::info("devices announced {}x{} {}", o.side_by_side ? 2 * width : width, height,
               o.format == "mjpeg" ? "MJPEG" : "GREY");
  return out;
}

// Waits for --wait-file; false when it did not appear in time.
bool wait_for_reader(const Options& o) {
  if (o.wait_file.empty()) return true;
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(o.wait_timeout_s);
  while (!std::filesystem::exists(o.wait_file)) {
    if (std::chrono::steady_clock::now() > until) {
      spdlog::error("{} did not appear within {} s (no reader streaming)", o.wait_file, o.wait_timeout_s);
      return false;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return true;
}

struct PlayStats {
  agvslam::Series write_ms;  // per pair
  std::size_t late = 0;      // pairs started more than half a period late
};

// One pair per period on an absolute schedule, each stamped with its due time.
PlayStats play(const Options& o, const Frames& f, const Jpegs& jpegs, Outputs& out, double rate_hz) {
  PlayStats st;
  cv::Mat sbs;
  const auto period_ns = static_cast<int64_t>(1e9 / rate_hz);
  const int64_t t0 = v4l2::monotonic_now_ns() + 1000000;
  for (std::size_t k = 0; k < f.left.size(); ++k) {
    const int64_t due = t0 + static_cast<int64_t>(k) * period_ns;
    timespec ts{static_cast<time_t>(due / 1000000000LL), static_cast<long>(due % 1000000000LL)};
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
    const int64_t start = v4l2::monotonic_now_ns();
    if (start - due > period_ns / 2) ++st.late;
    if (o.format == "mjpeg") {
      out.left->write_bytes(jpegs.left[k].data(), jpegs.left[k].size(), due);
      if (out.right) out.right->write_bytes(jpegs.right[k].data(), jpegs.right[k].size(), due);
    } else if (o.side_by_side) {
      cv::hconcat(f.left[k], f.right[k], sbs);
      out.left->write(sbs, due);
    } else {
      out.left->write(f.left[k], due);
      out.right->write(f.right[k], due);
    }
    st.write_ms.add(static_cast<double>(v4l2::monotonic_now_ns() - start) / 1e6);
  }
  return st;
}

void report(const Options& o, std::size_t frames, double rate_hz, const PlayStats& st) {
  spdlog::info(
      "sent {} frames at {} Hz; {} started more than half a period late; write per pair median {:.2f} ms, "
      "p95 {:.2f} ms, max {:.2f} ms",
      frames, rate_hz, st.late, st.write_ms.median(), st.write_ms.quantile(0.95), st.write_ms.max());
  std::printf("SENT %zu LATE %zu\n", frames, st.late);
  if (!o.json.empty()) {
    nlohmann::json j = {
        {"frames", frames},
        {"rate_hz", rate_hz},
        {"late", st.late},
        {"write_ms",
         {{"median", st.write_ms.median()}, {"p95", st.write_ms.quantile(0.95)}, {"max", st.write_ms.max()}}}};
    std::ofstream(o.json) << j.dump(2) << "\n";
  }
}

int run(const Options& o) {
  check_options(o);
  const auto ds = agvslam::io::open_dataset(o.dataset);
  std::size_t a = 0, b = 0;
  parse_range(o.frames, ds->size(), a, b);
  const double rate = o.rate_hz > 0 ? o.rate_hz : ds->rate_hz();
  spdlog::info(
      "agvslam-v4l2-feed: dataset {} ({}, {} frames, {} Hz), frames {}:{}, rate {} Hz, {} {}{}{}, manifest {}, "
      "wait-file {} (timeout {} s), start delay {} s, stamps {}, format {} (JPEG quality {})",
      ds->root(), ds->kind(), ds->size(), ds->rate_hz(), a, b, rate, o.side_by_side ? "side-by-side" : "left", o.left,
      o.side_by_side ? "" : " right ", o.side_by_side ? "" : o.right, o.manifest.empty() ? "-" : o.manifest,
      o.wait_file.empty() ? "-" : o.wait_file, o.wait_timeout_s, o.start_delay_s, o.stamp, o.format, o.jpeg_quality);

  const Frames frames = load_frames(o, *ds, a, b);
  if (!o.manifest.empty()) write_manifest(o.manifest, ds->root(), frames, a);
  if (o.dry_run) return 0;
  const Jpegs jpegs = o.format == "mjpeg" ? encode_jpegs(o, frames) : Jpegs{};
  Outputs out = open_outputs(o, frames.left.front().cols, frames.left.front().rows);
  if (!wait_for_reader(o)) return 1;
  if (o.start_delay_s > 0) std::this_thread::sleep_for(std::chrono::duration<double>(o.start_delay_s));
  report(o, frames.left.size(), rate, play(o, frames, jpegs, out, rate));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  spdlog::set_default_logger(spdlog::stderr_color_mt("feed"));
  CLI::App app{"agvslam-v4l2-feed: play a stereo sequence into V4L2 output devices (v4l2loopback) as GREY"};
  Options o;
  app.add_option("--dataset", o.dataset, "dataset folder (KITTI layout or EuRoC ASL)")->required();
  app.add_option("--left", o.left, "left output device (side by side: the one device)");
  app.add_option("--right", o.right, "right output device");
  app.add_flag("--side-by-side", o.side_by_side, "write left|right side by side into --left");
  app.add_option("--rate-hz", o.rate_hz, "frames per second (default: the dataset's rate)");
  app.add_option("--frames", o.frames, "A:B, frame range to play (B exclusive)");
  app.add_option("--manifest", o.manifest, "write index and pixel hashes of every frame played");
  app.add_flag("--dry-run", o.dry_run, "only load the frames and write the manifest");
  app.add_option("--wait-file", o.wait_file, "start playing once this file exists");
  app.add_option("--wait-timeout-s", o.wait_timeout_s, "give up waiting for --wait-file after this long");
  app.add_option("--start-delay-s", o.start_delay_s, "sleep this long before the first frame");
  app.add_option("--stamp", o.stamp,
                 "queue: both eyes carry the scheduled capture time (mmap + VIDIOC_QBUF); write: write(), the driver "
                 "stamps and numbers each eye when written")
      ->check(CLI::IsMember({"queue", "write"}));
  app.add_option("--format", o.format, "grey (default) or mjpeg (each frame a JPEG, as UVC cameras send)")
      ->check(CLI::IsMember({"grey", "mjpeg"}));
  app.add_option("--jpeg-quality", o.jpeg_quality, "JPEG quality for --format mjpeg (1..100)")
      ->check(CLI::Range(1, 100));
  app.add_option("--json", o.json, "write statistics as JSON");
  // A device that refuses the configuration (not an output device, size or format refused) is bad input.
  return agvslam::apps::parse_and_run(
      app, argc, argv, [&] { return run(o); },
      [](const std::exception& e) {
        const auto* device = dynamic_cast<const v4l2::V4l2Error*>(&e);
        return device != nullptr && device->configuration();
      });
}
