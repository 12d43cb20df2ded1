// Runs agvslam-dynamic on a short simulated sequence (written by agvslam-sim) and on the real KITTI 06 excerpt.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <regex>
#include <sstream>
#include <vector>

#include "common/test_data.h"

namespace agvslam {
namespace {
namespace fs = std::filesystem;

// One short scene1 sequence for all tests of this file (rendering is the slow part).
const std::string& scene1_sequence() {
  static const std::string dir = [] {
    const std::string d = test::make_temp_dir("agvslam-dynamic-tool") + "/scene1";
    std::string out;
    const int rc = test::run_command(
        test::tool_path("agvslam-sim") + " --scenario scene1 --seed 7 --squeeze-to 40 --threads 2 --out " + d, &out);
    EXPECT_EQ(rc, 0) << out;
    return d;
  }();
  return dir;
}

// agvslam-dynamic on the scene1 sequence into <its folder>/<name>, with `options` and --json <out>/result.json; logs go
// to stderr and are dropped, so the first line of stdout_text is stdout's first line. Returns the exit status.
int run_on_scene1(const std::string& name, const std::string& options, std::string& out, std::string& json_path,
                  std::string& stdout_text) {
  const std::string data = scene1_sequence();
  out = fs::path(data).parent_path().string() + "/" + name;
  json_path = out + "/result.json";
  return test::run_command("(" + test::tool_path("agvslam-dynamic") + " --dataset " + data + " --out " + out + " " +
                               options + " --json " + json_path + " 2>/dev/null)",
                           &stdout_text);
}

TEST(DynamicTool, WritesMasksOverlaysScoresAndJson) {
  const std::string data = scene1_sequence();
  std::string out, json_path, stdout_text;
  ASSERT_EQ(run_on_scene1("run", "--overlay-every 10", out, json_path, stdout_text), 0) << stdout_text;
  std::smatch m;
  const std::regex score_line(R"(^PRECISION ([0-9.]+) RECALL ([0-9.]+) IOU ([0-9.]+)\n)");
  ASSERT_TRUE(std::regex_search(stdout_text, m, score_line)) << stdout_text;
  EXPECT_NE(stdout_text.find("time per frame [ms]"), std::string::npos);
  EXPECT_NE(stdout_text.find("total"), std::string::npos);

  int masks = 0;
  for (const auto& e : fs::directory_iterator(out + "/mask")) {
    const cv::Mat mask = cv::imread(e.path().string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(mask.type(), CV_8UC1);
    ASSERT_EQ(mask.size(), cv::Size(752, 480));
    ++masks;
  }
  EXPECT_EQ(masks, 40);
  for (const char* name : {"000010.png", "000020.png", "000030.png"}) {
    const cv::Mat overlay = cv::imread(out + "/overlay/" + name);
    ASSERT_FALSE(overlay.empty()) << name;
    EXPECT_EQ(overlay.size(), cv::Size(2 * 752, 2 * 480));
  }

  std::ifstream f(json_path);
  const nlohmann::json j = nlohmann::json::parse(f);
  EXPECT_EQ(j["frames"]["detected"].get<int>(), 39);
  const int tp = j["true_positives"], fp = j["false_positives"], fn = j["false_negatives"];
  EXPECT_GT(tp + fn, 0) << "the person walks through the view";
  EXPECT_NEAR(j["precision"].get<double>(), tp + fp > 0 ? static_cast<double>(tp) / (tp + fp) : 1.0, 1e-9);
  EXPECT_NEAR(j["recall"].get<double>(), static_cast<double>(tp) / (tp + fn), 1e-9);
  EXPECT_NEAR(std::stod(m[2].str()), j["recall"].get<double>(), 1e-4);
  EXPECT_EQ(j["per_frame"].size(), 40u);
  EXPECT_TRUE(j["timings"].contains("total"));
  EXPECT_GT(j["timings"]["total"]["median_ms"].get<double>(), 0.0);

  // Each moving object's distance: bf over the median ground-truth disparity of its own pixels (disp_0/,
  // instance_0/, mask_0/), recomputed here for every scored object; the distance bins count every object.
  std::string calib_text;
  {
    std::ifstream cf(data + "/calib.txt");
    calib_text.assign(std::istreambuf_iterator<char>(cf), std::istreambuf_iterator<char>());
  }
  std::smatch p1;
  ASSERT_TRUE(std::regex_search(calib_text, p1, std::regex(R"(P1:\s+(\S+)\s+\S+\s+\S+\s+(\S+))"))) << calib_text;
  const double bf = -std::stod(p1[2].str());
  ASSERT_GT(bf, 0);
  int checked = 0;
  for (const auto& jf : j["per_frame"]) {
    if (!jf.contains("objects")) continue;
    char name[32];
    std::snprintf(name, sizeof(name), "%06d.png", jf["frame"].get<int>());
    const cv::Mat disp = cv::imread(data + "/disp_0/" + name, cv::IMREAD_UNCHANGED);
    const cv::Mat inst = cv::imread(data + "/instance_0/" + name, cv::IMREAD_UNCHANGED);
    const cv::Mat gt = cv::imread(data + "/mask_0/" + name, cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(disp.empty() || inst.empty() || gt.empty()) << name;
    for (const auto& o : jf["objects"]) {
      if (!o["moving"].get<bool>() || o["pixels"].get<int>() == 0) continue;
      std::vector<float> d;
      for (int y = 0; y < inst.rows; ++y) {
        for (int x = 0; x < inst.cols; ++x) {
          if (inst.at<uint8_t>(y, x) == o["id"].get<int>() && gt.at<uint8_t>(y, x) && disp.at<uint16_t>(y, x) > 0) {
            d.push_back(disp.at<uint16_t>(y, x) / 256.0f);
          }
        }
      }
      ASSERT_FALSE(d.empty()) << name;
      std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
      EXPECT_NEAR(o["distance_m"].get<double>(), bf / d[d.size() / 2], 1e-6) << name;
      EXPECT_GT(o["distance_m"].get<double>(), 0.5) << name;
      EXPECT_LT(o["distance_m"].get<double>(), 60.0) << name;
      ++checked;
    }
  }
  EXPECT_GT(checked, 0);

  // People and vehicles standing still (the person stops halfway): their own pixels (instance_0/) and of those the
  // ones in the written mask, recounted here; what the detector must leave to the SLAM.
  int64_t still_pixels = 0, still_masked = 0;
  for (const auto& jf : j["per_frame"]) {
    if (!jf.contains("objects")) continue;
    char name[32];
    std::snprintf(name, sizeof(name), "%06d.png", jf["frame"].get<int>());
    const cv::Mat inst = cv::imread(data + "/instance_0/" + name, cv::IMREAD_UNCHANGED);
    const cv::Mat mask = cv::imread(out + "/mask/" + name, cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(inst.empty() || mask.empty()) << name;
    for (const auto& o : jf["objects"]) {
      if (o["moving"].get<bool>()) continue;
      const cv::Mat own = inst == o["id"].get<int>();
      EXPECT_EQ(o["pixels"].get<int>(), cv::countNonZero(own)) << name;
      still_pixels += cv::countNonZero(own);
      still_masked += cv::countNonZero(own & mask);
    }
  }
  EXPECT_GT(still_pixels, 0) << "the person stands for a while";
  EXPECT_EQ(j["still_objects"]["pixels"].get<int64_t>(), still_pixels);
  EXPECT_EQ(j["still_objects"]["masked_pixels"].get<int64_t>(), still_masked);
  EXPECT_NE(stdout_text.find("people and vehicles standing still:"), std::string::npos);

  const nlohmann::json& rb = j["recall_breakdown"];
  int by_size = 0, by_distance = 0;
  for (const char* k : {"size_lt1500", "size_1500_5000", "size_5000_20000", "size_ge20000"})
    by_size += rb[k]["objects"].get<int>();
  for (const char* k : {"distance_lt4m", "distance_4_7m", "distance_7_12m", "distance_ge12m"}) {
    by_distance += rb[k]["objects"].get<int>();
    EXPECT_LE(rb[k]["found"].get<int>(), rb[k]["objects"].get<int>()) << k;
  }
  EXPECT_GT(by_size, 0);
  EXPECT_EQ(by_distance, by_size);
  // Objects within 4 m in full view (not cut by the left/right border, no nearer moving object's box over theirs),
  // recounted from objects.txt and the per-object distances.
  std::map<std::pair<int, int>, cv::Rect> boxes;
  std::ifstream objects_file(data + "/objects.txt");
  for (std::string line; std::getline(objects_file, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream in(line);
    int frame = 0, id = 0, moving = 0, x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    std::string object_class;
    ASSERT_TRUE(in >> frame >> id >> object_class >> moving >> x0 >> y0 >> x1 >> y1) << line;
    boxes[{frame, id}] = cv::Rect(cv::Point(x0, y0), cv::Point(x1 + 1, y1 + 1));
  }
  int full_view = 0, full_view_found = 0;
  int left = 0, left_found = 0, right = 0, right_found = 0, missed = 0;
  std::map<std::string, std::pair<int, int>> by_tracks;      // tracked-point bin -> (found, objects)
  std::map<std::string, std::map<std::string, int>> misses;  // distance band -> stage -> count
  for (const auto& jf : j["per_frame"]) {
    if (!jf.contains("objects")) continue;
    const int frame = jf["frame"].get<int>();
    for (const auto& o : jf["objects"]) {
      if (o["moving"].get<bool>() && o["pixels"].get<int>() >= 400) {
        const cv::Rect b = boxes.at({frame, o["id"].get<int>()});
        const bool hit = o["iou"].get<double>() >= 0.5;
        left += b.x <= 2;
        left_found += b.x <= 2 && hit;
        right += b.br().x >= 752 - 2;
        right_found += b.br().x >= 752 - 2 && hit;
        const int tracks = o["tracked_points"].get<int>();
        const std::string bin = tracks == 0   ? "tracks_0"
                                : tracks <= 2 ? "tracks_1_2"
                                : tracks <= 4 ? "tracks_3_4"
                                : tracks <= 9 ? "tracks_5_9"
                                              : "tracks_ge10";
        by_tracks[bin].first += hit;
        ++by_tracks[bin].second;
        if (!hit) {
          const double miss_m = o["distance_m"].get<double>();
          const std::string band = !(miss_m > 0)   ? "unknown"
                                   : miss_m < 4.0  ? "lt4m"
                                   : miss_m < 12.0 ? "4_12m"
                                                   : "ge12m";
          const std::string stage = o["in_mask"].get<int>() > 0          ? "outline_below_iou"
                                    : o["in_roi"].get<int>() > 0         ? "roi_not_masked"
                                    : o["dynamic_points"].get<int>() > 0 ? "no_roi"
                                    : o["tracked_points"].get<int>() > 0 ? "no_dynamic_point"
                                                                         : "no_track";
          ++misses[band][stage];
          ++missed;
        }
      }
      const double object_m = o["distance_m"].get<double>();
      if (!o["moving"].get<bool>() || o["pixels"].get<int>() < 400 || !(object_m > 0) || object_m >= 4.0) continue;
      const cv::Rect b = boxes.at({frame, o["id"].get<int>()});
      if (b.x <= 2 || b.br().x >= 752 - 2) continue;
      bool covered = false;
      for (const auto& other : jf["objects"]) {
        const double other_m = other["distance_m"].get<double>();
        if (other["id"] == o["id"] || !(other_m > 0) || other_m >= object_m) continue;
        covered = covered || (boxes.at({frame, other["id"].get<int>()}) & b).area() > 0;
      }
      if (covered) continue;
      ++full_view;
      full_view_found += o["iou"].get<double>() >= 0.5 ? 1 : 0;
    }
  }
  EXPECT_GT(full_view, 0);
  EXPECT_EQ(rb["full_view_lt4m"]["objects"].get<int>(), full_view);
  EXPECT_EQ(rb["full_view_lt4m"]["found"].get<int>(), full_view_found);
  EXPECT_LE(full_view, rb["distance_lt4m"]["objects"].get<int>());
  // Cut by the left / the right border, and each miss by the stage that lost it, recounted the same way.
  EXPECT_EQ(rb["border_left"]["objects"].get<int>(), left);
  EXPECT_EQ(rb["border_left"]["found"].get<int>(), left_found);
  EXPECT_EQ(rb["border_right"]["objects"].get<int>(), right);
  EXPECT_EQ(rb["border_right"]["found"].get<int>(), right_found);
  // By the tracked points on each object, recounted from the per-object diagnostics.
  int by_track_bins = 0;
  for (const char* k : {"tracks_0", "tracks_1_2", "tracks_3_4", "tracks_5_9", "tracks_ge10"}) {
    EXPECT_EQ(rb[k]["found"].get<int>(), by_tracks[k].first) << k;
    EXPECT_EQ(rb[k]["objects"].get<int>(), by_tracks[k].second) << k;
    by_track_bins += rb[k]["objects"].get<int>();
  }
  EXPECT_EQ(by_track_bins, by_size);
  int found = 0;
  for (const char* k : {"size_lt1500", "size_1500_5000", "size_5000_20000", "size_ge20000"})
    found += rb[k]["found"].get<int>();
  EXPECT_EQ(missed, by_size - found);
  EXPECT_GT(missed, 0);
  int counted = 0;
  for (const auto& [band, stages] : j["misses_by_stage"].items()) {
    for (const auto& [stage, n] : stages.items()) {
      EXPECT_EQ(n.get<int>(), misses[band][stage]) << band << " " << stage;
      counted += n.get<int>();
    }
  }
  EXPECT_EQ(counted, missed);
  // Recall by ground-truth image motion (eval::ground_truth_image_motion), recounted from the per-object motions.
  ASSERT_TRUE(j.contains("recall_by_ground_truth_motion"));
  EXPECT_NE(stdout_text.find("recall by ground-truth image motion"), std::string::npos);
  std::map<std::string, std::map<std::string, std::pair<int, int>>> motion;  // band -> bin -> (found, objects)
  int with_motion = 0;
  for (const auto& jf : j["per_frame"]) {
    if (!jf.contains("objects")) continue;
    for (const auto& o : jf["objects"]) {
      if (!o["moving"].get<bool>() || o["pixels"].get<int>() < 400 || !o.contains("gt_motion_px")) continue;
      const double object_m = o["distance_m"].get<double>();
      const std::string band = !(object_m > 0)   ? "unknown"
                               : object_m < 4.0  ? "lt4m"
                               : object_m < 12.0 ? "4_12m"
                                                 : "ge12m";
      const double motion_px = o["gt_motion_px"].get<double>();
      const std::string bin = !o["gt_motion_valid"].get<bool>() ? "visible_part_changed"
                              : motion_px < 1.0                 ? "lt1px"
                              : motion_px < 2.0                 ? "1_2px"
                              : motion_px < 4.0                 ? "2_4px"
                                                                : "ge4px";
      motion[band][bin].first += o["iou"].get<double>() >= 0.5 ? 1 : 0;
      motion[band][bin].second += 1;
      ++with_motion;
    }
  }
  EXPECT_GT(with_motion, 0);
  int motion_counted = 0;
  for (const auto& [band, bins] : j["recall_by_ground_truth_motion"].items()) {
    for (const auto& [bin, v] : bins.items()) {
      EXPECT_EQ(v["objects"].get<int>(), motion[band][bin].second) << band << " " << bin;
      EXPECT_EQ(v["found"].get<int>(), motion[band][bin].first) << band << " " << bin;
      motion_counted += v["objects"].get<int>();
    }
  }
  EXPECT_EQ(motion_counted, with_motion);
  // The person crossing in front of the standing AGV moves several px per frame.
  EXPECT_GT(motion["lt4m"]["2_4px"].second + motion["lt4m"]["ge4px"].second, 0);
}

TEST(DynamicTool, DumpRoisWritesOutlinesInstancesAndTheBandStage) {
  // --dump-rois (debugging): every ROI's outline as a PNG of the ROI's size, named in the JSON with the ROI's
  // dynamic points (previous x, y, current x, y, disparity); the reported objects as 8-bit ids, non-zero exactly
  // where the mask is. On scene1 the AGV stands, so the left-band stage runs on every frame and is reported.
  std::string out, json_path, stdout_text;
  ASSERT_EQ(run_on_scene1("dump", "--overlay-every 0 --dump-rois", out, json_path, stdout_text), 0) << stdout_text;
  std::ifstream f(json_path);
  const nlohmann::json j = nlohmann::json::parse(f);
  int outlines = 0, band_frames = 0;
  for (const auto& jf : j["per_frame"]) {
    char name[32];
    std::snprintf(name, sizeof(name), "%06d.png", jf["frame"].get<int>());
    const cv::Mat mask = cv::imread(out + "/mask/" + name, cv::IMREAD_UNCHANGED);
    const cv::Mat instances = cv::imread(out + "/instances/" + name, cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(mask.empty() || instances.empty()) << name;
    ASSERT_EQ(instances.type(), CV_8UC1);
    EXPECT_EQ(cv::countNonZero((instances > 0) != (mask > 0)), 0) << name;
    if (jf.contains("band")) {
      ++band_frames;
      EXPECT_LE(jf["band"]["static_segment_px"].get<double>(), 4.0) << name;
      EXPECT_GE(jf["band"]["tracks"].get<int>() + jf["band"]["corners"].get<int>(), 10) << name;
    }
    if (!jf.contains("rois")) continue;
    for (const auto& r : jf["rois"]) {
      ASSERT_TRUE(r.contains("outline_png") && r.contains("tracks")) << name;
      const cv::Mat outline = cv::imread(out + "/" + r["outline_png"].get<std::string>(), cv::IMREAD_UNCHANGED);
      ASSERT_FALSE(outline.empty()) << r["outline_png"];
      EXPECT_EQ(outline.cols, r["roi"][2].get<int>());
      EXPECT_EQ(outline.rows, r["roi"][3].get<int>());
      EXPECT_EQ(r["tracks"].size(), r["points"].get<std::size_t>());
      for (const auto& t : r["tracks"]) EXPECT_EQ(t.size(), 5u);
      ++outlines;
    }
  }
  EXPECT_GT(outlines, 0) << "the person crossing gets ROIs";
  EXPECT_EQ(band_frames, 39);
  EXPECT_TRUE(j["timings"].contains("band"));
}

TEST(DynamicTool, BadInputNamesTheOptionOrFolder) {
  const std::string data = scene1_sequence();
  const std::string out = test::make_temp_dir("agvslam-dynamic-bad");
  std::string text;
  EXPECT_EQ(test::run_command(
                test::tool_path("agvslam-dynamic") + " --dataset " + data + " --out " + out + " --frames 9:3", &text),
            2);
  EXPECT_NE(text.find("--frames"), std::string::npos) << text;
  EXPECT_EQ(test::run_command(
                test::tool_path("agvslam-dynamic") + " --dataset " + data + " --out " + out + " --frames 500:", &text),
            2);
  EXPECT_NE(text.find("40 frames"), std::string::npos) << text;
  EXPECT_EQ(
      test::run_command(test::tool_path("agvslam-dynamic") + " --dataset " + out + "/nothing --out " + out, &text), 2);
  EXPECT_NE(text.find("nothing"), std::string::npos) << text;
  const std::string bad_params = out + "/bad.yaml";
  std::ofstream(bad_params) << "epipolar:\n  a_epi_px: lots\n";
  EXPECT_EQ(test::run_command(test::tool_path("agvslam-dynamic") + " --dataset " + data + " --out " + out +
                                  " --params-dynamic " + bad_params,
                              &text),
            2);
  EXPECT_NE(text.find("epipolar.a_epi_px"), std::string::npos) << text;
  fs::remove_all(out);
}

TEST(DynamicTool, RealKittiParkedCarsGiveFewRegions) {
  AGVSLAM_REQUIRE_SHARED(root, "data/kitti06_f000-050");
  const std::string out = test::make_temp_dir("agvslam-dynamic-kitti");
  std::string text;
  ASSERT_EQ(test::run_command(test::tool_path("agvslam-dynamic") + " --dataset " + root + " --out " + out +
                                  " --overlay-every 0 --json " + out + "/r.json",
                              &text),
            0)
      << text;
  EXPECT_NE(text.find("PRECISION nan RECALL nan IOU nan"), std::string::npos) << text;
  EXPECT_NE(text.find("not scored"), std::string::npos);
  std::ifstream f(out + "/r.json");
  const nlohmann::json j = nlohmann::json::parse(f);
  const double per_frame = j["regions"]["per_frame"];
  std::printf("KITTI 06 f000-050: %.3f dynamic regions per frame\n", per_frame);
  EXPECT_LT(per_frame, 0.5);  // the excerpt's cars are parked: few false regions
  fs::remove_all(out);
}

}  // namespace
}  // namespace agvslam
