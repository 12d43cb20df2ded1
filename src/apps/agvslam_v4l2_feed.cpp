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

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <thread>
#include <ctime>

#include "agvslam/core/error.h"
#include "agvslam/drivers/v4l2/device.h"
#include "agvslam/drivers/v4l2/pixel_convert.h"
#include "agvslam/drivers/v4l2/stereo_camera.h"
#include "agvslam/io/dataset.h"

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

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(p * static_cast<double>(v.size() - 1) + 0.5))];
}

int run(const Options& o) {
  const auto ds = agvslam::io::open_dataset(o.dataset);
  std::size_t a = 0, b = 0;
  parse_range(o.frames, ds->size(), a, b);
  const double rate = o.rate_hz > 0 ? o.rate_hz : ds->rate_hz();
  spdlog::info("agvslam-v4l2-feed: dataset {} ({}, {} frames, {} Hz), frames {}:{}, rate {} Hz, {} {}{}{}, manifest {}, "
               "wait-file {} (timeout {} s), start delay {} s, stamps {}, format {} (JPEG quality {})",
               ds->root(), ds->kind(), ds->size(), ds->rate_hz(), a, b, rate, o.side_by_side ? "side-by-side" : "left",
               o.left, o.side_by_side ? "" : " right ", o.side_by_side ? "" : o.right,
               o.manifest.empty() ? "-" : o.manifest, o.wait_file.empty() ? "-" : o.wait_file, o.wait_timeout_s,
               o.start_delay_s, o.stamp, o.format, o.jpeg_quality);

  std::vector<cv::Mat> left, right;
  for (std::size_t i = a; i < b; ++i) {
    agvslam::StereoFrame f = ds->frame(i);
    left.push_back(f.left.isContinuous() ? f.left : f.left.clone());
    right.push_back(f.right.isContinuous() ? f.right : f.right.clone());
  }
  if (o.format == "mjpeg") {
    // libv4lconvert decodes JPEGs whose size is a multiple of the 16x16 block (as every UVC camera's is): crop.
    const cv::Rect roi(0, 0, left.front().cols & ~15, left.front().rows & ~15);
    if (roi.width != left.front().cols || roi.height != left.front().rows)
      spdlog::info("MJPEG: frames cropped to their top-left {}x{} (multiples of 16)", roi.width, roi.height);
    for (auto& m : left) m = m(roi).clone();
    for (auto& m : right) m = m(roi).clone();
  }
  const int w = left.front().cols, h = left.front().rows;
  if (!o.manifest.empty()) {
    const std::string tmp = o.manifest + ".tmp";
    {
      std::ofstream m(tmp);
      if (!m) throw InputError(o.manifest, "", "expected a writable file");
      m << "# agvslam-v4l2-feed manifest: index left_fnv1a64 right_fnv1a64; dataset " << ds->root() << " " << w << "x"
        << h << "\n";
      for (std::size_t k = 0; k < left.size(); ++k)
        m << (a + k) << " " << hex(v4l2::image_hash(left[k])) << " " << hex(v4l2::image_hash(right[k])) << "\n";
    }
    std::filesystem::rename(tmp, o.manifest);
  }
  if (o.dry_run) return 0;

  const bool mjpeg = o.format == "mjpeg";
  const auto pf = mjpeg ? v4l2::PixelFormat::kMjpeg : v4l2::PixelFormat::kGrey;
  // MJPEG: every frame encoded once before playing (3 channels of the grey value, OpenCV's 4:2:0 sampling).
  std::vector<std::vector<uint8_t>> jpeg_l, jpeg_r;
  if (mjpeg) {
    cv::Mat bgr, both;
    for (std::size_t k = 0; k < left.size(); ++k) {
      auto encode = [&](const cv::Mat& g, std::vector<std::vector<uint8_t>>& out) {
        cv::cvtColor(g, bgr, cv::COLOR_GRAY2BGR);
        out.emplace_back();
        cv::imencode(".jpg", bgr, out.back(), {cv::IMWRITE_JPEG_QUALITY, o.jpeg_quality});
      };
      if (o.side_by_side) {
        cv::hconcat(left[k], right[k], both);
        encode(both, jpeg_l);
      } else {
        encode(left[k], jpeg_l);
        encode(right[k], jpeg_r);
      }
    }
  }
  const auto mode = o.stamp == "write" ? v4l2::V4l2Output::Mode::kWrite : v4l2::V4l2Output::Mode::kQueue;
  std::unique_ptr<v4l2::V4l2Output> out_l, out_r;
  if (o.side_by_side) {
    out_l = std::make_unique<v4l2::V4l2Output>(o.left, 2 * w, h, mode, pf);
  } else {
    out_l = std::make_unique<v4l2::V4l2Output>(o.left, w, h, mode, pf);
    out_r = std::make_unique<v4l2::V4l2Output>(o.right, w, h, mode, pf);
  }
  out_l->announce();
  if (out_r) out_r->announce();
  spdlog::info("devices announced {}x{} {}", o.side_by_side ? 2 * w : w, h, mjpeg ? "MJPEG" : "GREY");

  if (!o.wait_file.empty()) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(o.wait_timeout_s);
    while (!std::filesystem::exists(o.wait_file)) {
      if (std::chrono::steady_clock::now() > until) {
        spdlog::error("{} did not appear within {} s (no reader streaming)", o.wait_file, o.wait_timeout_s);
        return 1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  if (o.start_delay_s > 0) std::this_thread::sleep_for(std::chrono::duration<double>(o.start_delay_s));

  cv::Mat sbs;
  std::vector<double> write_ms;
  std::size_t late = 0;
  const int64_t period_ns = static_cast<int64_t>(1e9 / rate);
  const int64_t t0 = v4l2::monotonic_now_ns() + 1000000;
  for (std::size_t k = 0; k < left.size(); ++k) {
    const int64_t due = t0 + static_cast<int64_t>(k) * period_ns;
    timespec ts{static_cast<time_t>(due / 1000000000LL), static_cast<long>(due % 1000000000LL)};
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
    const int64_t start = v4l2::monotonic_now_ns();
    if (start - due > period_ns / 2) ++late;
    if (mjpeg) {
      out_l->write_bytes(jpeg_l[k].data(), jpeg_l[k].size(), due);
      if (out_r) out_r->write_bytes(jpeg_r[k].data(), jpeg_r[k].size(), due);
    } else if (o.side_by_side) {
      cv::hconcat(left[k], right[k], sbs);
      out_l->write(sbs, due);
    } else {
      out_l->write(left[k], due);
      out_r->write(right[k], due);
    }
    write_ms.push_back(static_cast<double>(v4l2::monotonic_now_ns() - start) / 1e6);
  }
  spdlog::info("sent {} frames at {} Hz; {} started more than half a period late; write per pair median {:.2f} ms, "
               "p95 {:.2f} ms, max {:.2f} ms",
               left.size(), rate, late, percentile(write_ms, 0.5), percentile(write_ms, 0.95),
               percentile(write_ms, 1.0));
  std::printf("SENT %zu LATE %zu\n", left.size(), late);
  if (!o.json.empty()) {
    nlohmann::json j = {{"frames", left.size()}, {"rate_hz", rate}, {"late", late},
                        {"write_ms", {{"median", percentile(write_ms, 0.5)}, {"p95", percentile(write_ms, 0.95)},
                                      {"max", percentile(write_ms, 1.0)}}}};
    std::ofstream(o.json) << j.dump(2) << "\n";
  }
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
  app.add_option("--jpeg-quality", o.jpeg_quality, "JPEG quality for --format mjpeg (1..100)")->check(CLI::Range(1, 100));
  app.add_option("--json", o.json, "write statistics as JSON");
  try {
    app.parse(argc, argv);
    if (!o.dry_run && o.left.empty()) throw InputError("--left", "", "expected an output device");
    if (!o.dry_run && !o.side_by_side && o.right.empty())
      throw InputError("--right", "", "expected an output device (or --side-by-side)");
    if (o.rate_hz < 0) throw InputError("--rate-hz", "", "expected a rate > 0");
    return run(o);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  } catch (const InputError& e) {
    spdlog::error("{}", e.what());
    return 2;
  } catch (const v4l2::V4l2Error& e) {
    spdlog::error("{}", e.what());
    return e.configuration() ? 2 : 1;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
}
