// The detector on real stereo footage (../shared/data): KITTI 01's excerpt, a highway at ~90 km/h with painted
// hatching, dashed lines, a crash barrier and a car driving ahead.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <string>

#include "agvslam/dynamic/detector.h"
#include "agvslam/io/dataset.h"
#include "common/test_data.h"

namespace agvslam::dynamic {
namespace {

TEST(DynamicDetectorOnKitti01, TheStaticRoadStaysUnmaskedWhileTheCarAheadIsFound) {
  AGVSLAM_REQUIRE_SHARED(root, "data/kitti01_f000-050");
  const auto dataset = io::open_dataset(root);
  ASSERT_GE(dataset->size(), 40u);
  DynamicDetector detector(dataset->calibration(), DynamicDetectorConfig{}, stereo::StereoConfig{});
  // Rows 240 and below hold only the road, its markings and the barrier within ~10 m (nothing there moves); the car
  // ahead is 30-100 m away, in the band above them right of the centre.
  const cv::Rect near_road(0, 240, 1241, 136);
  const cv::Rect car_ahead(700, 130, 450, 105);
  int car_frames = 0, road_frames = 0, road_px_total = 0;
  std::string road;
  for (std::size_t i = 0; i < 40; ++i) {
    const DetectorResult r = detector.detect(dataset->frame(i));
    const cv::Rect image(0, 0, r.mask.image.cols, r.mask.image.rows);
    if (i >= 29) {
      // Frames 29-39 pass the hatching and the barrier close by: near tracks look off the ego-motion there through
      // their prediction's depth error at speed (depth_test.disparity_slack_*) and LK slipping a dash
      // (depth_test.leaving_margin_px, slip_*). A few frames keep a region the per-frame tests cannot clear.
      const int road_px = cv::countNonZero(r.mask.image(near_road & image));
      road_px_total += road_px;
      if (road_px > 500) {
        ++road_frames;
        road += " " + std::to_string(i) + ": " + std::to_string(road_px) + " px";
      }
    }
    if (i >= 9 && i <= 28 && cv::countNonZero(r.mask.image(car_ahead & image)) > 0) ++car_frames;
  }
  EXPECT_LE(road_frames, 3) << "static road masked in frames" << road;
  EXPECT_LE(road_px_total, 60000) << "static road masked in frames" << road;
  EXPECT_GE(car_frames, 14) << "the car ahead masked in " << car_frames << " of frames 9-28";
}

}  // namespace
}  // namespace agvslam::dynamic
