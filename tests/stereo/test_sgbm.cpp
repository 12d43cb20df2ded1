// StereoSgbm on real pairs with ground truth (KITTI 2015 #46, Middlebury 2014 Motorcycle-Q): whole-frame
// accuracy, and agreement of the ROI-only computation with the whole-frame one.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string>

#include "agvslam/stereo/sgbm.h"
#include "common/test_data.h"
#include "disparity_ground_truth.h"

namespace agvslam::stereo {
namespace {
using namespace agvslam::stereo::testing;

TEST(StereoSgbm, PfmReaderReadsMiddleburyGroundTruth) {
  AGVSLAM_REQUIRE_SHARED(dir, "data/disparity_pairs/middlebury2014_trainingQ_Motorcycle");
  const cv::Mat d = read_pfm(dir + "/disp0GT.pfm");
  ASSERT_EQ(d.size(), cv::Size(741, 497));
  int finite = 0;
  double lo = 1e9, hi = -1e9;
  for (int y = 0; y < d.rows; ++y) {
    for (int x = 0; x < d.cols; ++x) {
      const float v = d.at<float>(y, x);
      if (!std::isfinite(v)) continue;
      ++finite;
      lo = std::min(lo, static_cast<double>(v));
      hi = std::max(hi, static_cast<double>(v));
    }
  }
  // SOURCE.md: finite on 97.9 % of the pixels, 9.2 .. 62.9 px.
  EXPECT_NEAR(static_cast<double>(finite) / d.total(), 0.979, 0.005);
  EXPECT_NEAR(lo, 9.2, 0.1);
  EXPECT_NEAR(hi, 62.9, 0.1);
}

TEST(StereoSgbm, KittiWholeFrameD1BelowThreePercent) {
  AGVSLAM_REQUIRE_SHARED(dir, "data/disparity_pairs/kitti2015_training_000046");
  const Pair p = load_kitti(dir);
  ASSERT_FALSE(p.left.empty());
  ASSERT_FALSE(p.truth_px.empty());
  StereoSgbm sgbm(kitti_config());
  cv::Mat disparity_px;
  sgbm.compute(p.left, p.right, disparity_px);
  ASSERT_EQ(disparity_px.type(), CV_32FC1);
  ASSERT_EQ(disparity_px.size(), p.left.size());
  const BadRate r = kitti_d1(disparity_px, p.truth_px);
  EXPECT_EQ(r.evaluated, 55068);  // SOURCE.md
  EXPECT_GT(static_cast<double>(r.estimated) / r.evaluated, 0.85) << "density on ground-truth pixels";
  EXPECT_LT(r.rate, 0.03) << "D1 " << 100 * r.rate << " %";
  RecordProperty("kitti_d1_percent", std::to_string(100 * r.rate));
}

TEST(StereoSgbm, MiddleburyWholeFrameBad2BelowSixPercent) {
  AGVSLAM_REQUIRE_SHARED(dir, "data/disparity_pairs/middlebury2014_trainingQ_Motorcycle");
  const Pair p = load_middlebury(dir);
  ASSERT_FALSE(p.left.empty());
  ASSERT_FALSE(p.truth_px.empty());
  ASSERT_FALSE(p.nonocc.empty());
  StereoSgbm sgbm(middlebury_config());
  cv::Mat disparity_px;
  sgbm.compute(p.left, p.right, disparity_px);
  const BadRate r = middlebury_bad(disparity_px, p.truth_px, p.nonocc, 2.0f);
  EXPECT_GT(static_cast<double>(r.estimated) / r.evaluated, 0.80) << "density on non-occluded pixels";
  EXPECT_LT(r.rate, 0.06) << "bad-2.0 " << 100 * r.rate << " %";
  RecordProperty("middlebury_bad2_percent", std::to_string(100 * r.rate));
}

// Fraction of pixels inside `mask_rect` valid in both maps where they differ by more than tol_px.
double disagreement(const cv::Mat& a_px, const cv::Mat& b_px, const cv::Rect& rect, float tol_px, int* both_valid) {
  int both = 0, differ = 0;
  for (int y = rect.y; y < rect.y + rect.height; ++y) {
    for (int x = rect.x; x < rect.x + rect.width; ++x) {
      const float a = a_px.at<float>(y, x), b = b_px.at<float>(y, x);
      if (!(a > 0) || !(b > 0)) continue;
      ++both;
      if (std::abs(a - b) > tol_px) ++differ;
    }
  }
  *both_valid = both;
  return both > 0 ? static_cast<double>(differ) / both : 1.0;
}

TEST(StereoSgbm, RoiDisparityAgreesWithWholeFrame) {
  AGVSLAM_REQUIRE_SHARED(dir, "data/disparity_pairs/kitti2015_training_000046");
  const Pair p = load_kitti(dir);
  ASSERT_FALSE(p.left.empty());
  StereoSgbm sgbm(kitti_config());
  cv::Mat full_px;
  sgbm.compute(p.left, p.right, full_px);

  // Two overlapping ROIs (merged into one crop), one at the left border, one separate, one partly outside.
  const std::vector<cv::Rect> rois = {
      {400, 150, 120, 90}, {480, 200, 100, 80}, {40, 100, 120, 60}, {900, 250, 150, 100}, {1180, 300, 100, 100}};
  cv::Mat roi_px;
  sgbm.compute_rois(p.left, p.right, rois, roi_px);
  ASSERT_EQ(roi_px.size(), p.left.size());
  ASSERT_EQ(roi_px.type(), CV_32FC1);

  const cv::Rect image(cv::Point(0, 0), p.left.size());
  cv::Mat inside(p.left.size(), CV_8UC1, cv::Scalar(0));
  for (const cv::Rect& r : rois) inside(r & image).setTo(255);
  // Nothing outside the ROIs.
  for (int y = 0; y < roi_px.rows; ++y) {
    for (int x = 0; x < roi_px.cols; ++x) {
      if (inside.at<uint8_t>(y, x) == 0) {
        ASSERT_EQ(roi_px.at<float>(y, x), 0.0f) << x << "," << y;
      }
    }
  }
  for (const cv::Rect& r : rois) {
    const cv::Rect c = r & image;
    int both = 0, full_valid = 0, roi_valid = 0;
    const double bad = disagreement(roi_px, full_px, c, 1.0f, &both);
    for (int y = c.y; y < c.y + c.height; ++y) {
      for (int x = c.x; x < c.x + c.width; ++x) {
        full_valid += full_px.at<float>(y, x) > 0;
        roi_valid += roi_px.at<float>(y, x) > 0;
      }
    }
    if (full_valid == 0) {  // nothing measurable here (left of the search range): the ROI result agrees
      EXPECT_EQ(roi_valid, 0) << "ROI " << c;
      continue;
    }
    EXPECT_GT(both, 0.8 * full_valid) << "ROI " << c;
    EXPECT_GT(roi_valid, 0.8 * full_valid) << "ROI " << c;
    EXPECT_LT(bad, 0.03) << "ROI " << c << ": " << 100 * bad << " % differ by > 1 px";
  }

  // The single-ROI function returns the same values as the multi-ROI one for a separate ROI.
  cv::Mat one_px;
  sgbm.compute_roi(p.left, p.right, rois[3], one_px);
  ASSERT_EQ(one_px.size(), rois[3].size());
  EXPECT_EQ(cv::norm(one_px, roi_px(rois[3]), cv::NORM_INF), 0.0);
  // A ROI outside the image gives an empty result.
  sgbm.compute_roi(p.left, p.right, cv::Rect(5000, 0, 10, 10), one_px);
  EXPECT_TRUE(one_px.empty());
}

// Row step 2 (pairs of rows averaged, every column matched): against KITTI's ground truth in a large ROI it is
// about as accurate and dense as matching every row, every result row serves two image rows, and bad steps fail.
TEST(StereoSgbm, RowStepRoiKeepsKittiAccuracy) {
  AGVSLAM_REQUIRE_SHARED(dir, "data/disparity_pairs/kitti2015_training_000046");
  const Pair p = load_kitti(dir);
  ASSERT_FALSE(p.left.empty());
  ASSERT_FALSE(p.truth_px.empty());
  StereoSgbm sgbm(kitti_config());
  const cv::Rect roi(300, 120, 600, 200);
  cv::Mat every_row_px, row_pairs_px;
  sgbm.compute_roi(p.left, p.right, roi, every_row_px, 0, 1.0, 1);
  sgbm.compute_roi(p.left, p.right, roi, row_pairs_px, 0, 1.0, 2);
  ASSERT_EQ(row_pairs_px.size(), roi.size());
  ASSERT_EQ(row_pairs_px.type(), CV_32FC1);
  auto d1_in_roi = [&](const cv::Mat& roi_px) {
    cv::Mat full(p.left.size(), CV_32FC1, cv::Scalar(0)), truth(p.left.size(), CV_32FC1, cv::Scalar(0));
    roi_px.copyTo(full(roi));
    p.truth_px(roi).copyTo(truth(roi));
    return kitti_d1(full, truth);
  };
  const BadRate every_row = d1_in_roi(every_row_px), row_pairs = d1_in_roi(row_pairs_px);
  ASSERT_GT(every_row.evaluated, 10000);
  EXPECT_LT(row_pairs.rate, 0.05) << "D1 " << 100 * row_pairs.rate << " % (every row: " << 100 * every_row.rate
                                  << " %)";
  EXPECT_LT(row_pairs.rate, every_row.rate + 0.02);
  EXPECT_GT(row_pairs.estimated, 0.95 * every_row.estimated);
  for (int y = 0; y + 1 < roi.height; y += 2) {
    ASSERT_EQ(cv::norm(row_pairs_px.row(y), row_pairs_px.row(y + 1), cv::NORM_INF), 0.0)
        << "rows " << y << ", " << y + 1;
  }
  cv::Mat unused;
  EXPECT_THROW(sgbm.compute_roi(p.left, p.right, roi, unused, 0, 1.0, 3), cv::Exception);
}

TEST(StereoSgbm, CropCoversTheDisparityRange) {
  SgbmConfig c;
  c.num_disparities = 64;
  c.roi_margin_px = 10;
  c.block_size = 5;
  const StereoSgbm sgbm(c);
  const cv::Rect crop = sgbm.crop_for(cv::Rect(300, 100, 50, 40), cv::Size(752, 480));
  EXPECT_EQ(crop.x, 300 - 12 - 63 - 1);
  EXPECT_EQ(crop.y, 100 - 12);
  EXPECT_EQ(crop.br(), cv::Point(300 + 50 + 12, 100 + 40 + 12));
  const cv::Rect clipped = sgbm.crop_for(cv::Rect(10, 5, 50, 40), cv::Size(752, 480));
  EXPECT_EQ(clipped.tl(), cv::Point(0, 0));
}

TEST(StereoSgbm, ShiftedSyntheticPairGivesTheShift) {
  cv::Mat left(120, 200, CV_8UC1);
  cv::RNG rng(7);
  cv::Mat noise(30, 50, CV_8UC1);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 255);
  cv::resize(noise, left, left.size(), 0, 0, cv::INTER_CUBIC);
  // right(x) = left(x + 9): a front-parallel plane at disparity 9 px.
  cv::Mat right;
  const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, -9, 0, 1, 0);
  cv::warpAffine(left, right, shift, left.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  SgbmConfig c;
  c.num_disparities = 32;
  StereoSgbm sgbm(c);
  cv::Mat d;
  sgbm.compute(left, right, d);
  int valid = 0, good = 0;
  for (int y = 10; y < 110; ++y) {
    for (int x = 50; x < 190; ++x) {
      const float v = d.at<float>(y, x);
      if (v > 0) {
        ++valid;
        good += std::abs(v - 9.0f) < 0.25f;
      }
    }
  }
  EXPECT_GT(valid, 0.9 * 100 * 140);
  EXPECT_GT(good, 0.97 * valid);
  // Columns left of the search range are invalid.
  EXPECT_EQ(d.at<float>(60, 5), 0.0f);
}

TEST(StereoSgbm, RawConversionMarksInvalidAsZero) {
  cv::Mat raw = (cv::Mat_<int16_t>(1, 4) << -16, 0, 16 * 5 + 8, 16 * 40);
  cv::Mat px;
  sgbm_raw_to_px(raw, 0, px);
  EXPECT_EQ(px.at<float>(0, 0), 0.0f);
  EXPECT_EQ(px.at<float>(0, 1), 0.0f);
  EXPECT_FLOAT_EQ(px.at<float>(0, 2), 5.5f);
  EXPECT_FLOAT_EQ(px.at<float>(0, 3), 40.0f);
  sgbm_raw_to_px(raw, 10, px);  // min disparity 10: 5.5 is below the range -> invalid
  EXPECT_EQ(px.at<float>(0, 2), 0.0f);
  EXPECT_FLOAT_EQ(px.at<float>(0, 3), 40.0f);
}

}  // namespace
}  // namespace agvslam::stereo
