#include "dynamic_report.h"

#include <cmath>
#include <filesystem>
#include <utility>

#include "agvslam/dynamic/median.h"
#include "agvslam/eval/object_motion.h"
#include "agvslam/io/trajectory_io.h"
#include "dynamic_overlay.h"

namespace agvslam::apps::dynamic_tool {

namespace fs = std::filesystem;

namespace {

std::vector<std::pair<std::string, double>> stage_values(const dyn::StageTimings& t) {
  return {{"pyramid", t.pyramid_ms},
          {"tracking", t.tracking_ms},
          {"point_disparity", t.point_disparity_ms},
          {"epipolar", t.epipolar_ms},
          {"depth_test", t.depth_test_ms},
          {"multiframe", t.multiframe_ms},
          {"densify", t.densify_ms},
          {"grouping", t.grouping_ms},
          {"roi_disparity", t.roi_disparity_ms},
          {"slic", t.slic_ms},
          {"planes", t.planes_ms},
          {"boundaries", t.boundaries_ms},
          {"regions", t.regions_ms},
          {"motion_carve", t.motion_carve_ms},
          {"band", t.band_ms},
          {"features", t.features_ms},
          {"total", t.total_ms}};
}

// Per ground-truth object of a frame (moving or not): its visible moving pixels, the tracked and dynamic points on
// it, how much of it the ROIs and the mask cover, and the IoU of the detection matched to it (0 = missed). This
// tells at which stage an object was lost (no dynamic points, no ROI, or a poor outline).
// gt_instances (may be empty): each pixel's object id; with it, an object's pixels are its own ones only.
// gt_disparity_px (may be empty, the simulator's disp_0/): with it, each object's distance (bf over the median
// ground-truth disparity of its own pixels).
nlohmann::json object_diagnostics(const std::vector<agvslam::io::SceneObject>* objects, const cv::Mat& gt_mask,
                                  const cv::Mat& gt_instances, const cv::Mat& gt_disparity_px, double bf_px_m,
                                  const dyn::DetectorResult& r, const eval::FrameDetectionScore& f) {
  nlohmann::json out = nlohmann::json::array();
  if (objects == nullptr) return out;
  const cv::Rect frame_rect(cv::Point(0, 0), gt_mask.size());
  for (const auto& obj : *objects) {
    const cv::Rect box = obj.box & frame_rect;
    int pixels = 0, in_mask = 0, in_roi = 0, tracked = 0, dynamic = 0;
    auto own = [&](int x, int y) { return gt_instances.empty() || gt_instances.at<uint8_t>(y, x) == obj.id; };
    std::vector<float> disparities;
    for (int y = box.y; y < box.br().y; ++y) {
      const uint8_t* g = gt_mask.ptr<uint8_t>(y);
      const uint8_t* d = r.mask.image.ptr<uint8_t>(y);
      const float* gd = gt_disparity_px.empty() ? nullptr : gt_disparity_px.ptr<float>(y);
      for (int x = box.x; x < box.br().x; ++x) {
        // A moving object is its moving pixels; one standing still is its own instance pixels (none without
        // instance_0/: its box alone would count the background around it).
        if ((obj.moving ? !g[x] : gt_instances.empty()) || !own(x, y)) continue;
        ++pixels;
        if (gd != nullptr && gd[x] > 0) disparities.push_back(gd[x]);
        in_mask += d[x] ? 1 : 0;
        for (const auto& roi : r.rois) {
          if (roi.roi.contains(cv::Point(x, y))) {
            ++in_roi;
            break;
          }
        }
      }
    }
    for (const auto& p : r.points) {
      if (!p.tracked) continue;
      const cv::Point q(cvRound(p.cur_px.x), cvRound(p.cur_px.y));
      if (!box.contains(q) || (obj.moving && !gt_mask.at<uint8_t>(q)) || !own(q.x, q.y)) continue;
      ++tracked;
      dynamic += p.dynamic ? 1 : 0;
    }
    double iou = 0;
    for (const auto& d : f.detections) {
      if (d.matched_object_id == obj.id) iou = d.iou;
    }
    double distance_m = -1;  // unknown
    if (!disparities.empty() && bf_px_m > 0)
      distance_m = bf_px_m / static_cast<double>(dyn::median_in_place(disparities, 0.0f));
    out.push_back({{"id", obj.id},
                   {"class", obj.object_class},
                   {"moving", obj.moving},
                   {"pixels", pixels},
                   {"in_mask", in_mask},
                   {"in_roi", in_roi},
                   {"tracked_points", tracked},
                   {"dynamic_points", dynamic},
                   {"iou", iou},
                   {"distance_m", distance_m}});
  }
  return out;
}

// Per detected object: its box and size, the object it matched (-1 none) and how many of its pixels lie on
// moving ground truth (a false positive on a moving object is a split or merged outline, elsewhere a false alarm).
nlohmann::json detection_diagnostics(const eval::FrameDetectionScore& f, const cv::Mat& instances,
                                     const cv::Mat& gt_mask) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& d : f.detections) {
    // Instances are numbered in the order score_detection_instances lists them (increasing label), so the
    // detection's label is the one most of its box's instance pixels carry.
    std::map<int, int> count;
    for (int y = d.box.y; y < d.box.br().y; ++y)
      for (int x = d.box.x; x < d.box.br().x; ++x)
        if (const int k = instances.at<uint8_t>(y, x)) ++count[k];
    int label = 0, best = -1;
    for (const auto& [k, c] : count) {
      if (c > best) {
        best = c;
        label = k;
      }
    }
    int on_moving = 0;
    for (int y = d.box.y; y < d.box.br().y; ++y)
      for (int x = d.box.x; x < d.box.br().x; ++x)
        on_moving += instances.at<uint8_t>(y, x) == label && gt_mask.at<uint8_t>(y, x) ? 1 : 0;
    out.push_back({{"box", {d.box.x, d.box.y, d.box.width, d.box.height}},
                   {"pixels", d.pixels},
                   {"matched", d.matched_object_id},
                   {"iou", d.iou},
                   {"ignored", d.ignored},
                   {"on_moving", on_moving}});
  }
  return out;
}

std::string fmt(double v, const char* format = "%.4f") {
  char buf[64];
  std::snprintf(buf, sizeof(buf), format, v);
  return buf;
}

// The tracked points by test (and with --json-points each of them), and the multi-frame test's figures.
void add_points_json(const Options& o, const dyn::DetectorResult& result, const cv::Mat& gt_mask, nlohmann::json& jf) {
  int tracked = 0, epi = 0, depth = 0, multi = 0;
  for (const auto& p : result.points) {
    tracked += p.tracked ? 1 : 0;
    epi += p.dynamic_epipolar ? 1 : 0;
    depth += p.dynamic_depth ? 1 : 0;
    multi += p.dynamic_multiframe ? 1 : 0;
  }
  if (o.json_points) {
    nlohmann::json jp = nlohmann::json::array();
    for (const auto& p : result.points) {
      if (!p.tracked) continue;
      const cv::Point q(cvRound(p.cur_px.x), cvRound(p.cur_px.y));
      const int on_gt = gt_mask.empty() ? -1 : (gt_mask.at<uint8_t>(q) ? 1 : 0);
      jp.push_back({{"x", p.cur_px.x},
                    {"y", p.cur_px.y},
                    {"d", p.cur_disparity_px},
                    {"age", p.age},
                    {"densified", p.densified},
                    {"d_epi", p.d_epi_px},
                    {"t_epi", p.t_epi_px},
                    {"reproj", p.reprojection_px},
                    {"disp_res", p.disparity_residual_px},
                    {"mf", p.multiframe_px},
                    {"mf_disp", p.multiframe_disparity_residual_px},
                    {"epipolar", p.dynamic_epipolar},
                    {"depth", p.dynamic_depth},
                    {"multiframe", p.dynamic_multiframe},
                    {"dynamic", p.dynamic},
                    {"group", p.group},
                    {"on_gt", on_gt}});
    }
    jf["tracked_points"] = jp;
  }
  jf["points"] = {{"tracked", tracked}, {"epipolar", epi}, {"depth", depth}, {"multiframe", multi}};
  jf["multiframe"] = {{"valid", result.multiframe.valid},
                      {"frames_back", result.multiframe.frames_back},
                      {"translation_m", result.multiframe.translation_m},
                      {"candidates", result.multiframe.candidates},
                      {"flagged", result.multiframe.flagged},
                      {"confirmed", result.multiframe.confirmed},
                      {"a_reproj_px", result.multiframe.test.a_reproj_used_px},
                      {"a_disp_px", result.multiframe.test.a_disp_used_px}};
}

// Every ROI with an outline: its size, verdict, points and motion; with --dump-rois also its outline as a PNG
// (rois/<frame>_<k>.png, whatever its verdict) and its dynamic points' positions in both frames.
nlohmann::json rois_json(const Options& o, std::size_t frame, const dyn::DetectorResult& result,
                         const cv::Mat& gt_mask) {
  nlohmann::json jr = nlohmann::json::array();
  for (std::size_t k = 0; k < result.rois.size(); ++k) {
    const auto& roi = result.rois[k];
    if (roi.outline.empty()) continue;
    const int px = cv::countNonZero(roi.outline);
    const int on_gt = gt_mask.empty() ? -1 : cv::countNonZero(roi.outline & gt_mask(roi.roi));
    jr.push_back({{"roi", {roi.roi.x, roi.roi.y, roi.roi.width, roi.roi.height}},
                  {"pixels", px},
                  {"on_gt", on_gt},
                  {"points", roi.points.size()},
                  {"tracked_inside", roi.outline_stats.tracked_inside},
                  {"dynamic_inside", roi.outline_stats.dynamic_inside},
                  {"multiframe_tested_inside", roi.outline_stats.multiframe_tested_inside},
                  {"multiframe_dynamic_inside", roi.outline_stats.multiframe_dynamic_inside},
                  {"d", roi.mean_disparity_px},
                  {"motion", roi.outline_motion.apparent_motion_px},
                  {"motion_multiframe", roi.outline_motion_multiframe.apparent_motion_px},
                  {"verdict", dyn::to_string(roi.outline_verdict)},
                  {"coasted", roi.coasted},
                  {"median_offset", roi.outline_stats.median_offset_px},
                  {"object", roi.object_id},
                  {"motion_carve",
                   {{"ran", roi.motion_carve.ran},
                    {"blocks_tested", roi.motion_carve.blocks_tested},
                    {"blocks_static", roi.motion_carve.blocks_static},
                    {"pixels_removed", roi.motion_carve.pixels_removed}}}});
    if (o.dump_rois) {
      char name[48];
      std::snprintf(name, sizeof(name), "%06zu_%02zu.png", frame, k);
      write_png((fs::path(o.out_dir) / "rois" / name).string(), roi.outline);
      nlohmann::json tracks = nlohmann::json::array();
      for (int idx : roi.points) {
        const auto& p = result.points[static_cast<std::size_t>(idx)];
        tracks.push_back({p.prev_px.x, p.prev_px.y, p.cur_px.x, p.cur_px.y, p.cur_disparity_px});
      }
      jr.back()["outline_png"] = std::string("rois/") + name;
      jr.back()["tracks"] = tracks;
    }
  }
  return jr;
}

// The frame scored against the ground-truth masks (eqs. 12-14), with per-object and per-detection diagnostics and
// each moving object's ground-truth image motion since the last frame (eval/object_motion.h).
void score_frame(std::size_t i, std::size_t first, const agvslam::io::StereoDataset& dataset, const GroundTruth& gt,
                 const FrameTruth& truth, const eval::DetectionScoringConfig& scoring,
                 const dyn::DetectorResult& result, Totals& totals, nlohmann::json& jf) {
  std::vector<eval::GroundTruthObject> gt_objects;
  const auto it = gt.objects.find(static_cast<int>(i));
  if (it != gt.objects.end()) {
    for (const auto& obj : it->second) {
      if (obj.moving) gt_objects.push_back({obj.id, obj.box});
    }
  }
  const eval::FrameDetectionScore f =
      eval::score_detection_instances(result.mask.instances, truth.mask, gt_objects, scoring, truth.instances);
  totals.score.add(f);
  totals.instances_scored += truth.instances.empty() ? 0 : 1;
  jf["tp"] = f.true_positives;
  jf["fp"] = f.false_positives;
  jf["fn"] = f.false_negatives;
  jf["iou"] = f.matched_iou;
  jf["objects"] = object_diagnostics(it == gt.objects.end() ? nullptr : &it->second, truth.mask, truth.instances,
                                     truth.disparity_px, dataset.calibration().bf(), result, f);
  if (gt.poses && i < gt.poses->size() && i > first && !truth.instances.empty() && !truth.disparity_px.empty() &&
      !gt.last_instances.empty() && !gt.last_disparity_px.empty()) {
    const agvslam::SE3d T_now_then = (*gt.poses)[i].T_w_c.inverse() * (*gt.poses)[i - 1].T_w_c;
    for (auto& d : jf["objects"]) {
      if (!d["moving"].get<bool>()) continue;
      const eval::ObjectImageMotion m = eval::ground_truth_image_motion(
          gt.last_instances, gt.last_disparity_px, truth.instances, truth.disparity_px, d["id"].get<int>(),
          dataset.calibration().left, dataset.calibration().bf(), T_now_then);
      d["gt_motion_px"] = m.offset_px;
      d["gt_motion_valid"] = m.valid;
    }
  }
  for (const auto& d : jf["objects"]) {
    if (d["moving"].get<bool>()) continue;
    totals.still_pixels += d["pixels"].get<int>();
    totals.still_masked += d["in_mask"].get<int>();
  }
  if (it != gt.objects.end()) totals.breakdown.add(it->second, jf["objects"], truth.mask.size(), scoring);
  jf["detections"] = detection_diagnostics(f, result.mask.instances, truth.mask);
}

}  // namespace

GroundTruth load_ground_truth(const agvslam::io::StereoDataset& dataset) {
  GroundTruth gt;
  gt.has_masks = fs::is_directory(fs::path(dataset.root()) / "mask_0");
  const fs::path objects_path = fs::path(dataset.root()) / "objects.txt";
  if (gt.has_masks && fs::exists(objects_path)) gt.objects = agvslam::io::read_objects_file(objects_path.string());
  if (gt.has_masks) gt.poses = dataset.ground_truth();
  return gt;
}

void add_detected_frame(const Options& o, std::size_t i, std::size_t first, const agvslam::io::StereoDataset& dataset,
                        const GroundTruth& gt, const FrameTruth& truth, const eval::DetectionScoringConfig& scoring,
                        const dyn::DetectorResult& result, double detect_cpu_ms, Totals& totals, nlohmann::json& jf) {
  ++totals.frames_detected;
  for (const auto& [name, ms] : stage_values(result.timings)) totals.add_time(name, ms);
  // The detector's CPU time on this thread (all of it with --opencv-threads 1): robust to other load.
  totals.add_time("total_cpu", detect_cpu_ms);
  const int n_regions = static_cast<int>(result.mask.regions.size());
  totals.regions += n_regions;
  totals.frames_with_regions += n_regions > 0 ? 1 : 0;
  jf["regions"] = n_regions;
  if (result.band.ran) {
    jf["band"] = {{"static_segment_px", result.band.static_segment_px},
                  {"tracks", result.band.tracks},
                  {"corners", result.band.corners},
                  {"seeds", result.band.seeds.size()},
                  {"regions", result.band.regions.size()},
                  {"joined", result.band_joined},
                  {"objects", result.band_objects},
                  {"ms", result.timings.band_ms}};
  }
  if (result.band_driving_seeds > 0) {
    jf["band_driving"] = {{"seeds", result.band_driving_seeds}, {"dynamic", result.band_driving_dynamic}};
  }
  jf["unconfirmed_objects"] = result.unconfirmed_objects;  // found, not reported (confirm.min_box_iou)
  totals.unconfirmed += result.unconfirmed_objects;
  jf["dynamic_points"] = result.dynamic_point_count();
  add_points_json(o, result, truth.mask, jf);
  jf["mask_pixels"] = result.mask.pixel_count();
  jf["total_ms"] = result.timings.total_ms;
  jf["lk_levels"] = result.lk_levels;
  if (result.ground_plane.valid) {
    jf["ground_plane"] = {result.ground_plane.a, result.ground_plane.b, result.ground_plane.c};
  }
  jf["rois"] = rois_json(o, i, result, truth.mask);
  if (!truth.mask.empty()) score_frame(i, first, dataset, gt, truth, scoring, result, totals, jf);
}

void print_summary(bool scored, const eval::DetectionScoringConfig& scoring, Totals& totals) {
  const double nan = std::nan("");
  const eval::DetectionScore& score = totals.score;
  const double p = scored ? score.precision() : nan, r = scored ? score.recall() : nan,
               iou = scored ? score.mean_iou() : nan;
  std::printf("PRECISION %s RECALL %s IOU %s\n", fmt(p).c_str(), fmt(r).c_str(), fmt(iou).c_str());
  std::printf(
      "frames: %d detected (the first has no previous frame); %d regions, %.3f per frame, %d frames with regions\n",
      totals.frames_detected, totals.regions,
      totals.frames_detected > 0 ? static_cast<double>(totals.regions) / totals.frames_detected : 0.0,
      totals.frames_with_regions);
  if (scored) {
    std::printf(
        "objects (IoU >= %.2f, objects under %d px don't care; %s): TP %d FP %d FN %d, %d don't-care; "
        "false regions per 100 frames %.2f\n",
        scoring.min_iou, scoring.min_object_pixels,
        totals.instances_scored == score.frames() ? "each object its own pixels (instance_0/)"
        : totals.instances_scored == 0            ? "each object the moving pixels in its box (no instance_0/)"
                                                  : "instance_0/ for some frames only",
        score.true_positives(), score.false_positives(), score.false_negatives(), score.ignored_objects(),
        score.false_positives_per_100_frames());
    std::printf("pixels: precision %.4f recall %.4f IoU %.4f\n", score.pixel_precision(), score.pixel_recall(),
                score.pixel_iou());
    if (totals.still_pixels > 0) {
      std::printf("people and vehicles standing still: %.4f of their %lld pixels left unmasked\n",
                  1.0 - static_cast<double>(totals.still_masked) / static_cast<double>(totals.still_pixels),
                  static_cast<long long>(totals.still_pixels));
    }
    std::printf("%s\n", totals.breakdown.describe().c_str());
    std::printf("%s\n", totals.breakdown.describe_misses().c_str());
    if (totals.breakdown.has_motion()) std::printf("%s\n", totals.breakdown.describe_motion().c_str());
  } else {
    std::printf("no ground-truth masks (mask_0/) in the dataset: not scored\n");
  }
  std::printf("time per frame [ms]      median      p95\n");
  for (const auto& name : totals.stage_order) {
    std::printf("  %-20s %9.3f %8.3f\n", name.c_str(), totals.timings[name].median(),
                totals.timings[name].quantile(0.95));
  }
}

void write_json(const Options& o, const agvslam::io::StereoDataset& dataset, std::size_t first, std::size_t last,
                bool scored, const eval::DetectionScoringConfig& scoring, Totals& totals) {
  const eval::DetectionScore& score = totals.score;
  nlohmann::json j;
  j["dataset"] = dataset.root();
  j["frames"] = {{"first", first}, {"last", last}, {"detected", totals.frames_detected}};
  j["regions"] = {
      {"total", totals.regions},
      {"per_frame", totals.frames_detected > 0 ? static_cast<double>(totals.regions) / totals.frames_detected : 0.0},
      {"unconfirmed_objects", totals.unconfirmed}};
  if (scored) {
    j["scoring"] = {{"min_iou", scoring.min_iou},
                    {"min_object_pixels", scoring.min_object_pixels},
                    {"instance_frames", totals.instances_scored}};
    j["precision"] = score.precision();
    j["recall"] = score.recall();
    j["mean_iou"] = score.mean_iou();
    j["true_positives"] = score.true_positives();
    j["false_positives"] = score.false_positives();
    j["false_negatives"] = score.false_negatives();
    j["dont_care_objects"] = score.ignored_objects();
    j["false_regions_per_100_frames"] = score.false_positives_per_100_frames();
    j["pixel"] = {{"precision", score.pixel_precision()}, {"recall", score.pixel_recall()}, {"iou", score.pixel_iou()}};
    j["still_objects"] = {
        {"pixels", totals.still_pixels},
        {"masked_pixels", totals.still_masked},
        {"unmasked_fraction", totals.still_pixels > 0 ? 1.0 - static_cast<double>(totals.still_masked) /
                                                                  static_cast<double>(totals.still_pixels)
                                                      : 1.0}};
    j["recall_breakdown"] = totals.breakdown.to_json();
    j["misses_by_stage"] = totals.breakdown.misses_json();
    if (totals.breakdown.has_motion()) j["recall_by_ground_truth_motion"] = totals.breakdown.motion_json();
  }
  nlohmann::json jt;
  for (const auto& name : totals.stage_order) {
    jt[name] = {{"median_ms", totals.timings[name].median()}, {"p95_ms", totals.timings[name].quantile(0.95)}};
  }
  j["timings"] = jt;
  j["per_frame"] = totals.per_frame;
  std::string text = j.dump(2) + "\n";
  agvslam::io::write_file_atomically(o.json_path, text);
}

}  // namespace agvslam::apps::dynamic_tool
