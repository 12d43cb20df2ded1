// agvslam-dynamic: runs the dynamic-region detector (paper 004, III.A-B) over a stereo sequence.
//
//   agvslam-dynamic --dataset DIR --out DIR [--json FILE] [--frames A:B] [--params-dynamic params/dynamic.yaml]
//                   [--params-stereo params/stereo.yaml] [--calib FILE] [--overlay-every N]
//                   [--min-object-pixels N] [--min-iou X] [--semantic MODEL|off] [--params-semantic FILE]
//
// --semantic MODEL adds the semantic stage (agvslam/semantic/semantic_masker.h, params/semantic.yaml): segmented
// movable objects that move are fused with the detector's mask and scored with it; here it waits for every
// segmentation (fusion.synchronous), so the scores do not depend on timing. A model that cannot be loaded leaves
// the detector alone, with a warning.
//
// Writes <out>/mask/NNNNNN.png (8-bit, 255 = dynamic) for every frame, and every N-th frame an overlay
// <out>/overlay/NNNNNN.png with four panels like the paper's Figs. 3, 5, 7 and 8: (a) SGBM disparity of the
// whole frame, (b) tracked points (green static, red dynamic, orange densified dynamic) and the dynamic ROIs
// (yellow), (c) the ROIs' superpixels with occlusion boundaries in red and hinges in blue (tinted green where the
// photometric check found them moving with the background, magenta where they moved otherwise), (d) the mask
// and regions (red rectangles) against the ground truth where the dataset has one (green: correct, red: false,
// blue: missed pixels).
// Where the dataset has mask_0/ (the simulator), each frame after the first is scored as the paper does
// (eqs. 12-14, objects matched by IoU >= 0.5; each detector region is one detected object; with instance_0/ each
// ground-truth object is its own visible pixels, also where objects overlap; see agvslam/eval/detection_scoring.h).
// The first line of stdout is `PRECISION <p> RECALL <r> IOU <iou>` (fractions; nan without ground truth),
// followed by the counts, regions per frame and per-stage median/p95 times. Exit status: 0 on success, 2 on bad
// input (the message names the option, file or folder), 1 on any other failure.

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include <cstddef>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <string>

#include "agvslam/core/clock.h"
#include "agvslam/core/error.h"
#include "agvslam/dynamic/detector.h"
#include "agvslam/eval/detection_scoring.h"
#include "agvslam/io/dataset.h"
#include "agvslam/semantic/semantic_masker.h"
#include "agvslam/stereo/sgbm.h"
#include "agvslam/stereo/stereo_config.h"
#include "dynamic_options.h"
#include "dynamic_overlay.h"
#include "dynamic_report.h"
#include "tool_main.h"

namespace {

namespace fs = std::filesystem;
using agvslam::InputError;
using agvslam::thread_cpu_ms;
namespace dyn = agvslam::dynamic;
namespace eval = agvslam::eval;
// The tool's other files: its options (dynamic_options.h), images (dynamic_overlay.h) and report (dynamic_report.h).
using agvslam::apps::dynamic_tool::add_detected_frame;
using agvslam::apps::dynamic_tool::compose_overlay;
using agvslam::apps::dynamic_tool::frame_name;
using agvslam::apps::dynamic_tool::FrameTruth;
using agvslam::apps::dynamic_tool::GroundTruth;
using agvslam::apps::dynamic_tool::load_ground_truth;
using agvslam::apps::dynamic_tool::Options;
using agvslam::apps::dynamic_tool::print_summary;
using agvslam::apps::dynamic_tool::Totals;
using agvslam::apps::dynamic_tool::write_json;
using agvslam::apps::dynamic_tool::write_png;

// mask/, overlay/, rois/ and instances/ under --out.
void create_output_folders(const Options& o) {
  const fs::path out(o.out_dir);
  std::error_code ec;
  fs::create_directories(out / "mask", ec);
  if (ec) throw InputError("--out", o.out_dir, "a folder that can be created (" + ec.message() + ")");
  if (o.overlay_every > 0) fs::create_directories(out / "overlay", ec);
  if (o.dump_rois) {
    fs::create_directories(out / "rois", ec);
    fs::create_directories(out / "instances", ec);
  }
}

// The semantic stage of --semantic MODEL, or null (off, or a model that cannot be loaded: geometry alone).
std::unique_ptr<agvslam::semantic::SemanticMasker> open_semantic(const Options& o) {
  namespace sem = agvslam::semantic;
  if (o.semantic == "off") return nullptr;
  sem::SemanticConfig config =
      o.params_semantic.empty() ? sem::SemanticConfig{} : sem::load_semantic_config(o.params_semantic);
  config.model.path = o.semantic;
  config.fusion.synchronous = true;
  std::unique_ptr<sem::Segmenter> segmenter;
  try {
    segmenter = std::make_unique<sem::Segmenter>(config.model);
  } catch (const InputError& e) {
    spdlog::warn("--semantic: {}; continuing with the geometric detector alone", e.what());
    return nullptr;
  }
  spdlog::info("  semantic settings{}",
               o.params_semantic.empty() ? " (built-in defaults)" : " from " + o.params_semantic);
  for (const auto& line : config.describe()) spdlog::info("    {}", line);
  return std::make_unique<sem::SemanticMasker>(config, std::move(segmenter));
}

int run(const Options& o) {
  const auto dataset = agvslam::io::open_dataset(o.dataset, o.calib);
  std::size_t first = 0, last = 0;
  agvslam::io::parse_frame_range(o.frames, dataset->size(), "--frames", o.frames, first, last);

  const dyn::DynamicDetectorConfig dynamic_config =
      o.params_dynamic.empty() ? dyn::DynamicDetectorConfig{} : dyn::load_dynamic_config(o.params_dynamic);
  const agvslam::stereo::StereoConfig stereo_config =
      o.params_stereo.empty() ? agvslam::stereo::StereoConfig{} : agvslam::stereo::load_stereo_config(o.params_stereo);
  spdlog::info("agvslam-dynamic: {} dataset {} ({} frames, using {}..{})", dataset->kind(), dataset->root(),
               dataset->size(), first, last);
  spdlog::info("  calibration: {}", dataset->calibration().summary());
  spdlog::info("  detector settings{}",
               o.params_dynamic.empty() ? " (built-in defaults)" : " from " + o.params_dynamic);
  for (const auto& line : dynamic_config.describe()) spdlog::info("    {}", line);
  spdlog::info("  stereo settings{}", o.params_stereo.empty() ? " (built-in defaults)" : " from " + o.params_stereo);
  for (const auto& line : stereo_config.describe()) spdlog::info("    {}", line);

  GroundTruth gt = load_ground_truth(*dataset);
  eval::DetectionScoringConfig scoring;
  scoring.min_iou = o.min_iou;
  scoring.min_object_pixels = o.min_object_pixels;
  create_output_folders(o);
  const fs::path out(o.out_dir);

  cv::setNumThreads(o.opencv_threads);
  dyn::DynamicDetector detector(dataset->calibration(), dynamic_config, stereo_config);
  const std::unique_ptr<agvslam::semantic::SemanticMasker> semantic = open_semantic(o);
  agvslam::stereo::StereoSgbm display_sgbm(stereo_config.sgbm);
  dyn::DetectorResult result;
  Totals totals;
  int previous_dynamic_points = -1;
  for (std::size_t i = first; i <= last; ++i) {
    const agvslam::StereoFrame frame = dataset->frame(i);
    const double cpu_before_ms = thread_cpu_ms();
    detector.detect(frame, result);
    const double detect_cpu_ms = thread_cpu_ms() - cpu_before_ms;
    if (semantic) {
      agvslam::semantic::FrameCues cues;
      cues.previous_dynamic_points = previous_dynamic_points;
      semantic->process(i, frame.left, &result, cues);
      semantic->apply_fusion(result.mask);  // scored, written and drawn as the detector's own mask
    }
    previous_dynamic_points = result.dynamic_point_count();
    write_png((out / "mask" / frame_name(i)).string(), result.mask.image);
    if (o.dump_rois) write_png((out / "instances" / frame_name(i)).string(), result.mask.instances);
    FrameTruth truth;
    if (gt.has_masks) {
      truth.mask = dataset->ground_truth_mask(i);
      truth.instances = dataset->ground_truth_instances(i);        // empty without instance_0/
      truth.disparity_px = dataset->ground_truth_disparity_px(i);  // empty without disp_0/
    }
    nlohmann::json jf;
    jf["frame"] = i;
    if (result.has_previous)
      add_detected_frame(o, i, first, *dataset, gt, truth, scoring, result, detect_cpu_ms, totals, jf);
    totals.per_frame.push_back(jf);
    gt.last_instances = truth.instances;
    gt.last_disparity_px = truth.disparity_px;
    if (o.overlay_every > 0 && result.has_previous && (i - first) % static_cast<std::size_t>(o.overlay_every) == 0) {
      write_png((out / "overlay" / frame_name(i)).string(),
                compose_overlay(frame.left, frame.right, result, truth.mask, display_sgbm));
    }
    if ((i - first + 1) % 100 == 0) spdlog::info("  frame {}/{}", i - first + 1, last - first + 1);
  }

  if (semantic) {
    const agvslam::semantic::SemanticStats st = semantic->stats();
    spdlog::info(
        "semantic: {} frames sent to the network, {} segmented ({:.1f} ms each), {} carried late, {} dropped stale",
        st.requests, st.segmented, st.segmented ? st.segment_ms_total / static_cast<double>(st.segmented) : 0.0,
        st.late_results, st.stale_results);
  }
  const bool scored = gt.has_masks && totals.score.frames() > 0;
  print_summary(scored, scoring, totals);
  if (!o.json_path.empty()) write_json(o, *dataset, first, last, scored, scoring, totals);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // Logs go to stderr: stdout carries the results, starting with the PRECISION line.
  spdlog::set_default_logger(spdlog::stderr_color_mt("agvslam-dynamic"));
  CLI::App app{
      "agvslam-dynamic: dynamic-region detection (paper 004) over a stereo sequence, scored where the "
      "dataset has ground-truth masks"};
  Options o;
  app.add_option("--dataset", o.dataset, "sequence folder (KITTI layout as agvslam-sim writes it, or EuRoC)")
      ->required();
  app.add_option("--out", o.out_dir, "output folder: mask/ and overlay/")->required();
  app.add_option("--json", o.json_path, "write the scores, per-stage timings and per-frame figures as JSON");
  app.add_option("--frames", o.frames, "inclusive frame range A:B (default: all)");
  app.add_option("--params-dynamic", o.params_dynamic, "detector settings (params/dynamic.yaml; default: built-in)");
  app.add_option("--params-stereo", o.params_stereo, "stereo settings (params/stereo.yaml; default: built-in)");
  app.add_option("--calib", o.calib, "calibration file overriding the dataset's");
  app.add_option("--semantic", o.semantic,
                 "segmentation model (ONNX) whose moving objects join the detector's mask, or off (default)");
  app.add_option("--params-semantic", o.params_semantic, "params/semantic.yaml (with --semantic MODEL)");
  app.add_flag(
      "--dump-rois", o.dump_rois,
      "debugging: write every ROI's outline (kept or dropped) to rois/, the reported objects to instances/ (8-bit ids) "
      "and the ROIs' dynamic points to the --json output");
  app.add_flag("--json-points", o.json_points,
               "add every tracked point (position, disparity, age, tests, residuals) "
               "of every frame to the --json output (large)");
  app.add_option("--opencv-threads", o.opencv_threads,
                 "OpenCV worker threads (1: the detector on one core, as its timings are specified)")
      ->check(CLI::PositiveNumber);
  app.add_option("--overlay-every", o.overlay_every, "write an overlay every N frames (0 = none)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--min-object-pixels", o.min_object_pixels,
                 "ground-truth objects with fewer visible moving pixels are don't-care")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--min-iou", o.min_iou, "IoU for a detection to match an object (paper: 0.5)")
      ->check(CLI::Range(0.01, 1.0));
  return agvslam::apps::parse_and_run(app, argc, argv, [&] { return run(o); });
}
