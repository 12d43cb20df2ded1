// Quadtree-distributed FAST (paper 004, III.A).
#include <gtest/gtest.h>

#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "agvslam/core/error.h"
#include "agvslam/dynamic/quadtree_fast.h"
#include "common/test_data.h"
#include "synthetic_scene.h"

namespace agvslam::dynamic {
namespace {

TEST(QuadtreeDistribution, OneStrongestCornerPerQuadrant) {
  // Four clusters of 5 candidates, one per quadrant of a 64x64 area; responses known.
  std::vector<Corner> c;
  const cv::Point2f centres[4] = {{10, 10}, {50, 12}, {12, 50}, {48, 52}};
  for (int q = 0; q < 4; ++q) {
    for (int i = 0; i < 5; ++i) {
      c.push_back(
          {centres[q] + cv::Point2f(static_cast<float>(i), static_cast<float>(i % 2)), static_cast<float>(10 * q + i)});
    }
  }
  std::vector<cv::Rect2f> nodes;
  const std::vector<Corner> out = distribute_quadtree(c, cv::Rect2f(0, 0, 64, 64), 4, &nodes);
  ASSERT_EQ(out.size(), 4u);
  ASSERT_EQ(nodes.size(), 4u);
  // Sorted by response: the strongest of each cluster is response 10 q + 4.
  for (int k = 0; k < 4; ++k)
    EXPECT_EQ(out[static_cast<std::size_t>(k)].response, static_cast<float>(10 * (3 - k) + 4));
  for (std::size_t k = 0; k < out.size(); ++k) EXPECT_TRUE(nodes[k].contains(out[k].pt));
}

TEST(QuadtreeDistribution, ExactlyNAndStrongestPerNode) {
  cv::RNG rng(3);
  std::vector<Corner> c;
  for (int i = 0; i < 2000; ++i) {
    c.push_back({cv::Point2f(rng.uniform(16.f, 736.f), rng.uniform(16.f, 464.f)), rng.uniform(7.f, 80.f)});
  }
  const cv::Rect2f area(16, 16, 720, 448);
  for (int n : {10, 37, 100, 300, 777}) {
    std::vector<cv::Rect2f> nodes;
    const std::vector<Corner> out = distribute_quadtree(c, area, n, &nodes);
    ASSERT_EQ(static_cast<int>(out.size()), n);
    for (std::size_t k = 0; k < out.size(); ++k) {
      ASSERT_TRUE(nodes[k].contains(out[k].pt) || nodes[k].br() == cv::Point2f(area.br()));
      for (const Corner& cand : c) {  // nothing stronger in the same node
        if (nodes[k].contains(cand.pt)) {
          ASSERT_LE(cand.response, out[k].response);
        }
      }
    }
    // Nodes do not overlap (each holds exactly one of the returned corners).
    for (std::size_t a = 0; a < nodes.size(); ++a) {
      for (std::size_t b = a + 1; b < nodes.size(); ++b) ASSERT_LE((nodes[a] & nodes[b]).area(), 1e-3f);
    }
  }
}

TEST(QuadtreeDistribution, FewerCandidatesThanNReturnsAll) {
  std::vector<Corner> c = {{{20, 20}, 5}, {{21, 20}, 6}, {{200, 100}, 7}};
  const auto out = distribute_quadtree(c, cv::Rect2f(0, 0, 300, 200), 50);
  EXPECT_EQ(out.size(), 3u);
  // Identical positions cannot be separated: one node, the strongest wins.
  std::vector<Corner> same = {{{20, 20}, 5}, {{20, 20}, 9}, {{20, 20}, 1}};
  const auto one = distribute_quadtree(same, cv::Rect2f(0, 0, 64, 64), 10);
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one[0].response, 9.f);
  EXPECT_TRUE(distribute_quadtree({}, cv::Rect2f(0, 0, 64, 64), 10).empty());
}

cv::Mat textured_image(cv::Size size, double contrast, int seed) {
  return testing::make_texture(std::max(size.width, size.height), 128, contrast,
                               static_cast<uint64_t>(seed))(cv::Rect(cv::Point(0, 0), size))
      .clone();
}

TEST(QuadtreeFast, UniformOnATexturedImageAndExactlyN) {
  const cv::Mat img = textured_image({752, 480}, 160, 21);
  QuadtreeFastConfig cfg;
  cfg.target_count = 300;
  QuadtreeFast fast(cfg);
  std::vector<Corner> corners;
  QuadtreeStats stats;
  fast.detect(img, corners, &stats, true);
  ASSERT_EQ(corners.size(), 300u);
  EXPECT_GT(stats.candidates, 600);
  ASSERT_EQ(stats.node_rects.size(), corners.size());
  // Every node holds its corner (no empty node) and nodes tile the area without overlap; and every 90x90
  // cell (nodes are ~33 px on average, at most a few times that where corners are sparse) holds a corner.
  const int b = cfg.border_px;
  double node_area = 0;
  for (std::size_t k = 0; k < corners.size(); ++k) {
    EXPECT_TRUE(stats.node_rects[k].contains(corners[k].pt));
    node_area += stats.node_rects[k].area();
  }
  EXPECT_LE(node_area, (752.0 - 2 * b) * (480.0 - 2 * b) + 1.0);
  for (int y = b; y + 90 <= 480 - b; y += 90) {
    for (int x = b; x + 90 <= 752 - b; x += 90) {
      int n = 0;
      for (const Corner& c : corners)
        n += cv::Rect(x, y, 90, 90).contains(cv::Point(static_cast<int>(c.pt.x), static_cast<int>(c.pt.y)));
      EXPECT_GE(n, 1) << "empty cell at " << x << "," << y;
    }
  }
  // Inside the border only.
  for (const Corner& c : corners) {
    EXPECT_GE(c.pt.x, b);
    EXPECT_GE(c.pt.y, b);
    EXPECT_LT(c.pt.x, 752 - b);
    EXPECT_LT(c.pt.y, 480 - b);
  }
}

TEST(QuadtreeFast, NoCornersOnFlatPartsAndNoEmptyTexturedCell) {
  cv::Mat img = textured_image({752, 480}, 160, 22);
  img(cv::Rect(376, 0, 376, 480)).setTo(120);  // right half flat
  QuadtreeFast fast;
  std::vector<Corner> corners;
  fast.detect(img, corners);
  EXPECT_EQ(corners.size(), 300u);
  for (const Corner& c : corners) EXPECT_LT(c.pt.x, 380.f);
  for (int y = 16; y + 90 <= 464; y += 90) {
    for (int x = 16; x + 90 <= 376; x += 90) {
      int n = 0;
      for (const Corner& c : corners)
        n += cv::Rect(x, y, 90, 90).contains(cv::Point(static_cast<int>(c.pt.x), static_cast<int>(c.pt.y)));
      EXPECT_GE(n, 1) << "empty textured cell at " << x << "," << y;
    }
  }
}

TEST(QuadtreeFast, WeakCellsFallBackToTheLowerThreshold) {
  // Left half: strong texture. Right half: faint texture whose FAST scores stay below the normal threshold.
  cv::Mat img = textured_image({752, 480}, 160, 23);
  cv::Mat faint = textured_image({376, 480}, 35, 24);
  faint.copyTo(img(cv::Rect(376, 0, 376, 480)));
  std::vector<cv::KeyPoint> strong_right;
  cv::FAST(faint, strong_right, 20, true);
  ASSERT_LT(strong_right.size(), 20u) << "the faint half should have (almost) no corners at threshold 20";

  QuadtreeFast fast;
  std::vector<Corner> corners;
  QuadtreeStats stats;
  fast.detect(img, corners, &stats);
  EXPECT_GT(stats.weak_cells, 50);
  int right = 0;
  for (const Corner& c : corners) right += c.pt.x >= 380.f;
  EXPECT_GT(right, 60) << "the faint half still gets corners through the fallback threshold";

  // Without the fallback (min_threshold = threshold) the faint half stays nearly empty.
  QuadtreeFastConfig no_fallback;
  no_fallback.min_threshold = no_fallback.threshold;
  QuadtreeFast strict(no_fallback);
  strict.detect(img, corners);
  right = 0;
  for (const Corner& c : corners) right += c.pt.x >= 380.f;
  EXPECT_LT(right, 20);
}

// Both ways of finding the candidates give the same corners, bit for bit and in the same order, on images where
// the two-pass extraction pays (textured: few weak cells) and where it does not (EuRoC's plain walls, a faint half).
void expect_same_extraction(const cv::Mat& grey, const std::string& what) {
  QuadtreeFast one, two;
  one.set_extraction(QuadtreeFast::Extraction::kSinglePass);
  two.set_extraction(QuadtreeFast::Extraction::kTwoPass);
  std::vector<Corner> a, b;
  QuadtreeStats sa, sb;
  one.detect(grey, a, &sa);
  two.detect(grey, b, &sb);
  EXPECT_EQ(sa.candidates, sb.candidates) << what;
  EXPECT_EQ(sa.weak_cells, sb.weak_cells) << what;
  ASSERT_EQ(a.size(), b.size()) << what;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].pt, b[i].pt) << what << ", corner " << i;
    ASSERT_EQ(a[i].response, b[i].response) << what << ", corner " << i;
  }
}

TEST(QuadtreeFast, TwoPassExtractionFindsTheSinglePassCorners) {
  expect_same_extraction(textured_image({752, 480}, 160, 21), "textured");
  cv::Mat half = textured_image({752, 480}, 160, 23);
  textured_image({376, 480}, 35, 24).copyTo(half(cv::Rect(376, 0, 376, 480)));
  expect_same_extraction(half, "strong left half, faint right half");
  AGVSLAM_REQUIRE_SHARED(euroc, "data/euroc_v101_f000-094/mav0/cam0/data");
  AGVSLAM_REQUIRE_SHARED(kitti, "data/kitti06_f000-050/image_l");
  for (const std::string& dir : {euroc, kitti}) {
    std::vector<cv::String> files;
    cv::glob(dir + "/*.png", files);
    ASSERT_GE(files.size(), 40u) << dir;
    for (std::size_t i = 0; i < files.size(); i += 10)
      expect_same_extraction(cv::imread(files[i], cv::IMREAD_GRAYSCALE), files[i]);
  }
}

TEST(QuadtreeFast, InvalidConfigNamesTheField) {
  QuadtreeFastConfig c;
  c.min_threshold = 30;  // above threshold
  try {
    c.validate("params/dynamic.yaml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "features.min_threshold");
  }
  c = QuadtreeFastConfig{};
  c.target_count = 0;
  EXPECT_THROW(QuadtreeFast{c}, InputError);
}

}  // namespace
}  // namespace agvslam::dynamic
