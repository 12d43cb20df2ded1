// OrbExtractor: counts and levels, spread over the image, descriptors bit-equal to cv::ORB::compute on the same
// keypoints, intensity-centroid angles, the dynamic mask, buffer reuse. On a simulator frame and on real EuRoC
// and KITTI images.
#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "agvslam/features/orb_extractor.h"
#include "agvslam/io/dataset.h"
#include "common/test_data.h"
#include "feature_test_data.h"

namespace agvslam::features {
namespace {

cv::Mat euroc_left(const std::string& root) {
  const auto level = spdlog::get_level();
  spdlog::set_level(spdlog::level::err);
  const io::EurocDataset dataset(root);
  const StereoFrame f = dataset.frame(40);
  spdlog::set_level(level);
  return f.left;
}

const cv::Mat& sim_left() {
  static const cv::Mat left = testing::render_sim("scene4", 60).left;
  return left;
}

// Checks per-keypoint invariants and returns the count per level.
std::vector<int> check_keypoints(const OrbExtractor& ex, const KeypointSet& set, cv::Size image_size) {
  std::vector<int> per_level(static_cast<std::size_t>(ex.config().n_levels), 0);
  EXPECT_EQ(set.descriptors.rows, static_cast<int>(set.keypoints.size()));
  EXPECT_EQ(set.descriptors.cols, 32);
  EXPECT_EQ(set.descriptors.type(), CV_8UC1);
  int previous_level = 0;
  for (const cv::KeyPoint& k : set.keypoints) {
    EXPECT_GE(k.octave, previous_level) << "keypoints are grouped by level, ascending";
    previous_level = k.octave;
    EXPECT_LT(k.octave, ex.config().n_levels);
    const float s = ex.scale_factors()[static_cast<std::size_t>(k.octave)];
    const cv::Size sz = ex.level_size(image_size, k.octave);
    const float xl = k.pt.x / s, yl = k.pt.y / s;
    EXPECT_NEAR(xl, std::round(xl), 1e-3) << "level coordinates are whole pixels";
    EXPECT_GE(xl, kOrbEdgeThreshold - 0.01f);
    EXPECT_GE(yl, kOrbEdgeThreshold - 0.01f);
    EXPECT_LT(xl, sz.width - kOrbEdgeThreshold + 0.01f);
    EXPECT_LT(yl, sz.height - kOrbEdgeThreshold + 0.01f);
    EXPECT_FLOAT_EQ(k.size, 31.0f * s);
    EXPECT_GE(k.angle, 0.0f);
    EXPECT_LT(k.angle, 360.0f);
    EXPECT_GE(k.response, static_cast<float>(ex.config().min_fast_threshold));
    ++per_level[static_cast<std::size_t>(k.octave)];
  }
  return per_level;
}

TEST(OrbExtractor, FeaturesPerLevelFollowTheLevelAreaAndSumToTheTotal) {
  OrbExtractorConfig c;
  const std::vector<int> area = c.features_per_level();
  ASSERT_EQ(area.size(), 8u);
  int sum = 0;
  for (int n : area) sum += n;
  EXPECT_EQ(sum, 1200);
  // Area: each level gets 1/1.44 of the previous one.
  EXPECT_EQ(area[0], 388);
  for (std::size_t l = 1; l + 1 < area.size(); ++l) EXPECT_NEAR(area[l], area[l - 1] / 1.44, 1.0) << l;
  c.level_allocation = LevelAllocation::kSide;
  const std::vector<int> side = c.features_per_level();
  EXPECT_EQ(side[0], 261);  // ORB-SLAM2 / OpenCV: 1200 * (1 - 1/1.2) / (1 - 1.2^-8)
  for (std::size_t l = 1; l + 1 < side.size(); ++l) EXPECT_NEAR(side[l], side[l - 1] / 1.2, 1.0) << l;
}

TEST(OrbExtractor, PyramidLevelsAndScalesMatchOpenCvOrb) {
  OrbExtractorConfig c;
  c.n_levels = 5;
  c.scale_factor = 1.5;
  OrbExtractor ex(c);
  const cv::Mat& img = sim_left();
  KeypointSet set;
  ex.extract(img, cv::Mat(), set);
  ASSERT_EQ(ex.pyramid().size(), 5u);
  for (int l = 0; l < 5; ++l) {
    const double s = std::pow(1.5, l);
    EXPECT_NEAR(ex.scale_factors()[static_cast<std::size_t>(l)], s, 1e-5);
    EXPECT_NEAR(ex.inv_scale_factors()[static_cast<std::size_t>(l)], 1.0 / s, 1e-6);
    EXPECT_NEAR(ex.level_sigma2()[static_cast<std::size_t>(l)], s * s, 1e-4);
    EXPECT_NEAR(ex.inv_level_sigma2()[static_cast<std::size_t>(l)], 1.0 / (s * s), 1e-6);
    EXPECT_EQ(ex.pyramid()[static_cast<std::size_t>(l)].cols, cvRound(img.cols / s)) << l;
    EXPECT_EQ(ex.pyramid()[static_cast<std::size_t>(l)].rows, cvRound(img.rows / s)) << l;
  }
  // Level 0 is the image itself; level 1 is OpenCV's bit-exact bilinear resize of it.
  EXPECT_EQ(cv::norm(ex.pyramid()[0], img, cv::NORM_INF), 0);
  cv::Mat level1;
  cv::resize(img, level1, ex.pyramid()[1].size(), 0, 0, cv::INTER_LINEAR_EXACT);
  EXPECT_EQ(cv::norm(ex.pyramid()[1], level1, cv::NORM_INF), 0);
  const std::vector<int> per_level = check_keypoints(ex, set, img.size());
  const std::vector<int> wanted = c.features_per_level();
  for (int l = 0; l < 5; ++l) {
    EXPECT_GE(per_level[static_cast<std::size_t>(l)], 0.9 * wanted[static_cast<std::size_t>(l)]) << l;
    EXPECT_LE(per_level[static_cast<std::size_t>(l)], wanted[static_cast<std::size_t>(l)]) << l;
  }
}

void expect_count_and_levels(const cv::Mat& img, const char* what) {
  OrbExtractor ex;
  KeypointSet set;
  ex.extract(img, cv::Mat(), set);
  const std::vector<int> per_level = check_keypoints(ex, set, img.size());
  std::printf("%s: %zu keypoints, per level", what, set.keypoints.size());
  for (int n : per_level) std::printf(" %d", n);
  std::printf(" (%d candidates, %d cells retried)\n", ex.stats().candidates, ex.stats().retry_cells);
  EXPECT_GE(set.keypoints.size(), 1140u) << what;  // 95 % of 1200
  EXPECT_LE(set.keypoints.size(), 1200u) << what;
  for (std::size_t l = 0; l < per_level.size(); ++l) {
    EXPECT_GE(per_level[l], 0.85 * ex.features_per_level()[l]) << what << " level " << l;
    EXPECT_LE(per_level[l], ex.features_per_level()[l]) << what << " level " << l;
  }
}

TEST(OrbExtractor, ExtractsAboutTheRequestedCountOnEveryLevel) {
  expect_count_and_levels(sim_left(), "simulator scene4 #60");
  AGVSLAM_REQUIRE_SHARED(euroc, "data/euroc_v101_f000-094");
  expect_count_and_levels(euroc_left(euroc), "EuRoC V1_01 #40");
  AGVSLAM_REQUIRE_SHARED(kitti, "data/kitti06_f000-050");
  expect_count_and_levels(cv::imread(kitti + "/image_l/000010.png", cv::IMREAD_GRAYSCALE), "KITTI 06 #10");
}

// Descriptors computed by OpenCV's ORB on our keypoints (its own pyramid, blur and pattern) are identical.
void expect_descriptors_equal_opencv(const cv::Mat& img, const char* what) {
  OrbExtractor ex;
  KeypointSet set;
  ex.extract(img, cv::Mat(), set);
  auto orb = cv::ORB::create(1200, 1.2f, 8, 31, 0, 2, cv::ORB::HARRIS_SCORE, 31, 20);
  std::vector<cv::KeyPoint> cv_keypoints = set.keypoints;
  cv::Mat cv_descriptors;
  orb->compute(img, cv_keypoints, cv_descriptors);
  // OpenCV drops keypoints within 31 level-0 px of the border (edgeThreshold); the rest keep their order.
  ASSERT_GE(cv_keypoints.size(), 0.85 * set.keypoints.size()) << what;
  std::size_t j = 0;
  int compared = 0, equal = 0;
  std::vector<int> levels_compared(8, 0);
  for (std::size_t i = 0; i < set.keypoints.size() && j < cv_keypoints.size(); ++i) {
    if (set.keypoints[i].pt != cv_keypoints[j].pt || set.keypoints[i].octave != cv_keypoints[j].octave) continue;
    ++compared;
    ++levels_compared[static_cast<std::size_t>(cv_keypoints[j].octave)];
    const int d = descriptor_distance(set.descriptors.ptr<uint8_t>(static_cast<int>(i)),
                                      cv_descriptors.ptr<uint8_t>(static_cast<int>(j)));
    equal += d == 0;
    EXPECT_EQ(d, 0) << what << ": keypoint " << i << " level " << cv_keypoints[j].octave << " angle "
                    << cv_keypoints[j].angle;
    ++j;
  }
  EXPECT_EQ(static_cast<std::size_t>(compared), cv_keypoints.size()) << what;
  for (int l = 0; l < 8; ++l) EXPECT_GT(levels_compared[static_cast<std::size_t>(l)], 0) << what << " level " << l;
  std::printf("%s: %d of %d descriptors equal to cv::ORB::compute's\n", what, equal, compared);
}

TEST(OrbExtractor, DescriptorsEqualOpenCvOrbComputeOnTheSameKeypoints) {
  expect_descriptors_equal_opencv(sim_left(), "simulator");
  AGVSLAM_REQUIRE_SHARED(euroc, "data/euroc_v101_f000-094");
  expect_descriptors_equal_opencv(euroc_left(euroc), "EuRoC");
  AGVSLAM_REQUIRE_SHARED(kitti, "data/kitti06_f000-050");
  expect_descriptors_equal_opencv(cv::imread(kitti + "/image_l/000010.png", cv::IMREAD_GRAYSCALE), "KITTI");
}

TEST(OrbExtractor, DescriptorsEqualOpenCvForAnyAngle) {
  // Same keypoints, angles swept over the circle: the rotated pattern rounds exactly like OpenCV's.
  OrbExtractor ex;
  KeypointSet set;
  const cv::Mat& img = sim_left();
  ex.extract(img, cv::Mat(), set);
  cv::RNG rng(7);
  for (cv::KeyPoint& k : set.keypoints) k.angle = rng.uniform(0.0f, 360.0f);
  cv::Mat ours(static_cast<int>(set.keypoints.size()), 32, CV_8UC1);
  // The extractor's blurred pyramid is private: recompute it the way OpenCV's ORB does (bordered, blurred ROI).
  std::vector<cv::Mat> blurred;
  for (const cv::Mat& level : ex.pyramid()) {
    cv::Mat ext;
    cv::copyMakeBorder(level, ext, 8, 8, 8, 8, cv::BORDER_REFLECT_101);
    cv::Mat roi = ext(cv::Rect(8, 8, level.cols, level.rows));
    cv::Mat out;
    cv::GaussianBlur(roi, out, cv::Size(7, 7), 2, 2, cv::BORDER_REFLECT_101);
    blurred.push_back(out);
  }
  compute_orb_descriptors(blurred, ex.scale_factors(), set.keypoints, ours);
  auto orb = cv::ORB::create(1200, 1.2f, 8, 31, 0, 2, cv::ORB::HARRIS_SCORE, 31, 20);
  std::vector<cv::KeyPoint> cv_keypoints = set.keypoints;
  cv::Mat theirs;
  orb->compute(img, cv_keypoints, theirs);
  std::size_t j = 0;
  int compared = 0, differing = 0;
  for (std::size_t i = 0; i < set.keypoints.size() && j < cv_keypoints.size(); ++i) {
    if (set.keypoints[i].pt != cv_keypoints[j].pt) continue;
    ++compared;
    differing +=
        descriptor_distance(ours.ptr<uint8_t>(static_cast<int>(i)), theirs.ptr<uint8_t>(static_cast<int>(j))) != 0;
    ++j;
  }
  EXPECT_GT(compared, 1000);
  EXPECT_EQ(differing, 0);
}

TEST(OrbExtractor, AngleIsTheIntensityCentroidDirection) {
  OrbExtractor ex;
  KeypointSet set;
  ex.extract(sim_left(), cv::Mat(), set);
  int checked = 0;
  for (std::size_t i = 0; i < set.keypoints.size(); i += 7) {
    const cv::KeyPoint& k = set.keypoints[i];
    const cv::Mat& img = ex.pyramid()[static_cast<std::size_t>(k.octave)];
    const float s = ex.scale_factors()[static_cast<std::size_t>(k.octave)];
    const int cx = cvRound(k.pt.x / s), cy = cvRound(k.pt.y / s);
    double m10 = 0, m01 = 0;
    for (int v = -15; v <= 15; ++v) {
      for (int u = -15; u <= 15; ++u) {
        if (u * u + v * v > 15 * 15 + 15) continue;  // the rounded disc of radius 15 (OpenCV's umax)
        const double val = img.at<uint8_t>(cy + v, cx + u);
        m10 += u * val;
        m01 += v * val;
      }
    }
    double expected = std::atan2(m01, m10) * 180.0 / CV_PI;
    if (expected < 0) expected += 360.0;
    double diff = std::abs(expected - k.angle);
    diff = std::min(diff, 360.0 - diff);
    EXPECT_LT(diff, 1.0) << "keypoint " << i;  // fastAtan2 is accurate to ~0.3 degrees; the disc rim differs
    ++checked;
  }
  EXPECT_GT(checked, 100);
}

// Spread: every final quadtree node holds one keypoint, the nodes hold every corner (so every textured cell is
// represented), and no region of the image holds a pile.
void expect_spread(const cv::Mat& img, const char* what) {
  OrbExtractor ex;
  ex.set_collect_nodes(true);
  KeypointSet set;
  ex.extract(img, cv::Mat(), set);
  for (int l = 0; l < ex.config().n_levels; ++l) {
    const std::vector<cv::Rect>& nodes = ex.nodes(l);
    const float s = ex.scale_factors()[static_cast<std::size_t>(l)];
    std::vector<int> hits(nodes.size(), 0);
    int kps = 0;
    for (const cv::KeyPoint& k : set.keypoints) {
      if (k.octave != l) continue;
      ++kps;
      const cv::Point p(cvRound(k.pt.x / s), cvRound(k.pt.y / s));
      int inside = 0;
      for (std::size_t n = 0; n < nodes.size(); ++n) {
        if (nodes[n].contains(p)) {
          ++hits[n];
          ++inside;
        }
      }
      EXPECT_EQ(inside, 1) << what << " level " << l << ": each keypoint lies in exactly one node";
    }
    int empty = 0, piles = 0;
    for (int h : hits) {
      empty += h == 0;
      piles += h > 1;
    }
    EXPECT_EQ(piles, 0) << what << " level " << l;
    EXPECT_LE(empty, 3) << what << " level " << l << ": only the weakest overshoot nodes (<= 3) lose their keypoint";
    EXPECT_GE(static_cast<int>(nodes.size()), kps);
  }
  // Level 0, 60 px blocks: blocks with corners (FAST at the retry threshold) hold a keypoint of some level.
  const int block = 60;
  const int bx = (img.cols - 2 * kOrbEdgeThreshold) / block, by = (img.rows - 2 * kOrbEdgeThreshold) / block;
  std::vector<int> counts(static_cast<std::size_t>(bx * by), 0);
  for (const cv::KeyPoint& k : set.keypoints) {
    const int i = static_cast<int>((k.pt.x - kOrbEdgeThreshold) / block);
    const int j = static_cast<int>((k.pt.y - kOrbEdgeThreshold) / block);
    if (i >= 0 && j >= 0 && i < bx && j < by) ++counts[static_cast<std::size_t>(j * bx + i)];
  }
  int textured = 0, represented = 0, max_count = 0;
  for (int j = 0; j < by; ++j) {
    for (int i = 0; i < bx; ++i) {
      std::vector<cv::KeyPoint> corners;
      cv::FAST(img(cv::Rect(kOrbEdgeThreshold + i * block, kOrbEdgeThreshold + j * block, block, block)), corners,
               ex.config().min_fast_threshold, true);
      const int c = counts[static_cast<std::size_t>(j * bx + i)];
      max_count = std::max(max_count, c);
      if (corners.size() < 3) continue;
      ++textured;
      represented += c > 0;
    }
  }
  const double mean = static_cast<double>(set.keypoints.size()) / (bx * by);
  std::printf("%s: %d of %d textured 60 px blocks hold keypoints; at most %d per block (mean %.1f)\n", what,
              represented, textured, max_count, mean);
  EXPECT_GE(represented, 0.97 * textured) << what;
  EXPECT_LE(max_count, 4.0 * mean) << what << ": a pile";
}

TEST(OrbExtractor, KeypointsAreSpreadByTheQuadtree) {
  expect_spread(sim_left(), "simulator");
  AGVSLAM_REQUIRE_SHARED(euroc, "data/euroc_v101_f000-094");
  expect_spread(euroc_left(euroc), "EuRoC");
}

// No keypoint (= descriptor patch centre) lies within mask_dilation_px * scale of a dynamic pixel.
void expect_mask_respected(const cv::Mat& img, const cv::Mat& mask, const OrbExtractorConfig& c, const char* what) {
  OrbExtractor ex(c);
  KeypointSet set;
  ex.extract(img, mask, set);
  std::vector<cv::Point> dynamic_pixels;
  cv::findNonZero(mask, dynamic_pixels);
  ASSERT_FALSE(dynamic_pixels.empty());
  int violations = 0;
  for (const cv::KeyPoint& k : set.keypoints) {
    const double r = c.mask_dilation_px * ex.scale_factors()[static_cast<std::size_t>(k.octave)];
    double nearest = 1e9;
    for (const cv::Point& p : dynamic_pixels) {
      nearest = std::min(nearest, std::hypot(static_cast<double>(p.x) - k.pt.x, static_cast<double>(p.y) - k.pt.y));
    }
    if (nearest <= r) ++violations;
  }
  EXPECT_EQ(violations, 0) << what;
  EXPECT_GT(ex.stats().masked_candidates, 0) << what;
  const double free_fraction = 1.0 - cv::countNonZero(mask) / static_cast<double>(mask.total());
  EXPECT_GE(set.keypoints.size(), 0.8 * free_fraction * c.n_features) << what;
  std::printf("%s: %zu keypoints outside the mask (%.0f %% of the image free), %d corners masked\n", what,
              set.keypoints.size(), 100 * free_fraction, ex.stats().masked_candidates);
}

TEST(OrbExtractor, NoKeypointInsideTheDilatedDynamicMask) {
  const cv::Mat& img = sim_left();
  cv::Mat mask = cv::Mat::zeros(img.size(), CV_8UC1);
  cv::rectangle(mask, cv::Rect(300, 60, 120, 330), cv::Scalar(255), cv::FILLED);  // a person-sized block
  cv::circle(mask, cv::Point(620, 300), 45, cv::Scalar(255), cv::FILLED);
  mask.at<uint8_t>(200, 100) = 255;  // a single pixel
  OrbExtractorConfig c;
  expect_mask_respected(img, mask, c, "default dilation");
  c.mask_dilation_px = 0;
  expect_mask_respected(img, mask, c, "dilation 0");
  c.mask_dilation_px = 12;
  expect_mask_respected(img, mask, c, "dilation 12");
  c.mask_dilation_px = 5;
  const cv::Mat ones = mask / 255;  // any non-zero value marks a dynamic pixel
  expect_mask_respected(img, ones, c, "mask of ones");
}

TEST(OrbExtractor, SimulatorGroundTruthMaskOfAWalkingPerson) {
  // scene1: the stationary AGV sees a person cross; frame 118 has the person in view.
  const testing::SimPair p = testing::render_sim("scene1", 118);
  ASSERT_GT(cv::countNonZero(p.mask), 2000);
  expect_mask_respected(p.left, p.mask, OrbExtractorConfig{}, "scene1 #118 ground-truth mask");
}

TEST(OrbExtractor, AnEmptyMaskChangesNothing) {
  const cv::Mat& img = sim_left();
  OrbExtractor ex;
  KeypointSet a, b;
  ex.extract(img, cv::Mat(), a);
  ex.extract(img, cv::Mat::zeros(img.size(), CV_8UC1), b);
  ASSERT_EQ(a.keypoints.size(), b.keypoints.size());
  for (std::size_t i = 0; i < a.keypoints.size(); ++i) EXPECT_EQ(a.keypoints[i].pt, b.keypoints[i].pt);
  EXPECT_EQ(cv::norm(a.descriptors, b.descriptors, cv::NORM_INF), 0);
}

TEST(OrbExtractor, ReusesBuffersAndIsDeterministic) {
  const cv::Mat& img = sim_left();
  OrbExtractor ex;
  KeypointSet set;
  ex.extract(img, cv::Mat(), set);
  const cv::Mat first_descriptors = set.descriptors.clone();
  const std::vector<cv::KeyPoint> first_keypoints = set.keypoints;
  const uint8_t* descriptor_data = set.descriptors.data;
  const cv::KeyPoint* keypoint_data = set.keypoints.data();
  const uint8_t* level1 = ex.pyramid()[1].data;
  ex.extract(img, cv::Mat(), set);
  EXPECT_EQ(set.descriptors.data, descriptor_data);
  EXPECT_EQ(set.keypoints.data(), keypoint_data);
  EXPECT_EQ(ex.pyramid()[1].data, level1);
  ASSERT_EQ(set.keypoints.size(), first_keypoints.size());
  for (std::size_t i = 0; i < first_keypoints.size(); ++i) {
    EXPECT_EQ(set.keypoints[i].pt, first_keypoints[i].pt);
    EXPECT_EQ(set.keypoints[i].angle, first_keypoints[i].angle);
  }
  EXPECT_EQ(cv::norm(set.descriptors, first_descriptors, cv::NORM_INF), 0);

  // A caller that keeps a shallow copy of the descriptors keeps its data: the next call writes elsewhere.
  const cv::Mat shared = set.descriptors;
  ex.extract(cv::Mat(img.size(), CV_8UC1, cv::Scalar(0)) + img * 0.5, cv::Mat(), set);
  EXPECT_NE(set.descriptors.data, shared.data);
  EXPECT_EQ(cv::norm(shared, first_descriptors, cv::NORM_INF), 0);
}

TEST(OrbExtractor, FlatImageGivesNoKeypoints) {
  OrbExtractor ex;
  KeypointSet set;
  ex.extract(cv::Mat(480, 752, CV_8UC1, cv::Scalar(90)), cv::Mat(), set);
  EXPECT_TRUE(set.keypoints.empty());
  EXPECT_EQ(set.descriptors.rows, 0);
}

TEST(OrbExtractor, DescriptorDistanceCountsDifferingBits) {
  uint8_t a[32] = {}, b[32] = {};
  EXPECT_EQ(descriptor_distance(a, b), 0);
  b[0] = 0x81;
  b[31] = 0xff;
  b[17] = 0x10;
  EXPECT_EQ(descriptor_distance(a, b), 11);
}

}  // namespace
}  // namespace agvslam::features
