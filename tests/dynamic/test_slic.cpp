// SLIC (paper 004, eqs. 5-7): plain and incremental variants on a real image crop, connectivity, adherence.
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <queue>

#include "agvslam/dynamic/slic.h"
#include "common/test_data.h"
#include "synthetic_scene.h"

namespace agvslam::dynamic {
namespace {
namespace fs = std::filesystem;

// Every label 0 .. count-1 is used and is one 4-connected region.
void expect_connected_labels(const cv::Mat& labels, int count) {
  ASSERT_EQ(labels.type(), CV_32SC1);
  std::vector<int> size(static_cast<std::size_t>(count), 0);
  for (int y = 0; y < labels.rows; ++y) {
    for (int x = 0; x < labels.cols; ++x) {
      const int l = labels.at<int32_t>(y, x);
      ASSERT_GE(l, 0);
      ASSERT_LT(l, count);
      ++size[static_cast<std::size_t>(l)];
    }
  }
  for (int s : size) ASSERT_GT(s, 0);
  cv::Mat seen(labels.size(), CV_8UC1, cv::Scalar(0));
  std::vector<int> components(static_cast<std::size_t>(count), 0);
  for (int y = 0; y < labels.rows; ++y) {
    for (int x = 0; x < labels.cols; ++x) {
      if (seen.at<uint8_t>(y, x)) continue;
      const int l = labels.at<int32_t>(y, x);
      ++components[static_cast<std::size_t>(l)];
      std::queue<cv::Point> q;
      q.push({x, y});
      seen.at<uint8_t>(y, x) = 1;
      while (!q.empty()) {
        const cv::Point p = q.front();
        q.pop();
        const cv::Point nb[4] = {{p.x + 1, p.y}, {p.x - 1, p.y}, {p.x, p.y + 1}, {p.x, p.y - 1}};
        for (const cv::Point& n : nb) {
          if (n.x < 0 || n.y < 0 || n.x >= labels.cols || n.y >= labels.rows) continue;
          if (seen.at<uint8_t>(n) || labels.at<int32_t>(n) != l) continue;
          seen.at<uint8_t>(n) = 1;
          q.push(n);
        }
      }
    }
  }
  for (int c : components) EXPECT_EQ(c, 1);
}

cv::Mat real_crop() {
  const auto dir = agvslam::test::shared_path("data/euroc_v101_f000-094/mav0/cam0/data");
  if (!dir) return {};
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(*dir)) names.push_back(e.path().string());
  std::sort(names.begin(), names.end());
  const cv::Mat img = cv::imread(names.at(40), cv::IMREAD_GRAYSCALE);
  return img(cv::Rect(300, 100, 160, 200)).clone();
}

TEST(Slic, IncrementalAgreesWithPlainAndDoesLessWork) {
  AGVSLAM_REQUIRE_SHARED(dir, "data/euroc_v101_f000-094/mav0/cam0/data");
  const cv::Mat crop = real_crop();
  ASSERT_FALSE(crop.empty());
  Slic slic;
  cv::Mat plain, incremental;
  SlicStats sp, si;
  const int np = slic.segment(crop, plain, false, &sp);
  const int ni = slic.segment(crop, incremental, true, &si);
  expect_connected_labels(plain, np);
  expect_connected_labels(incremental, ni);
  EXPECT_EQ(sp.seeds, si.seeds);
  EXPECT_NEAR(np, sp.seeds, 0.25 * sp.seeds);
  EXPECT_NEAR(ni, si.seeds, 0.25 * si.seeds);

  // Labels are renumbered by the connectivity step in raster order; compare superpixels through the best
  // matching label (majority overlap) of the plain result for each incremental label.
  std::vector<std::map<int, int>> overlap(static_cast<std::size_t>(ni));
  for (int y = 0; y < crop.rows; ++y) {
    for (int x = 0; x < crop.cols; ++x)
      ++overlap[static_cast<std::size_t>(incremental.at<int32_t>(y, x))][plain.at<int32_t>(y, x)];
  }
  long agree = 0;
  for (const auto& m : overlap) {
    int best = 0;
    for (const auto& kv : m) best = std::max(best, kv.second);
    agree += best;
  }
  const double agreement = static_cast<double>(agree) / static_cast<double>(crop.total());
  EXPECT_GE(agreement, 0.95) << "pixel agreement " << agreement;
  EXPECT_LT(si.distance_evaluations, sp.distance_evaluations / 2)
      << "incremental " << si.distance_evaluations << " vs plain " << sp.distance_evaluations;
  RecordProperty("agreement", std::to_string(agreement));
  RecordProperty("evaluations_plain", std::to_string(sp.distance_evaluations));
  RecordProperty("evaluations_incremental", std::to_string(si.distance_evaluations));
  // Work per iteration: the plain variant evaluates about 4 (2S)^2 / S^2 distances per pixel every round.
  ASSERT_FALSE(sp.evaluations_per_iteration.empty());
  EXPECT_GT(sp.evaluations_per_iteration[0], 3 * static_cast<int64_t>(crop.total()));
  EXPECT_LT(si.evaluations_per_iteration.back(), sp.evaluations_per_iteration.back() / 2);
}

TEST(Slic, SuperpixelsFollowAStrongEdge) {
  // Two flat regions with a vertical step edge at x = 53 (not on the seed grid), plus noise.
  cv::Mat img(120, 160, CV_8UC1, cv::Scalar(60));
  img(cv::Rect(53, 0, 107, 120)).setTo(180);
  testing::add_noise(img, 3.0, 1);
  for (bool incremental : {false, true}) {
    Slic slic;
    cv::Mat labels;
    const int n = slic.segment(img, labels, incremental, nullptr);
    expect_connected_labels(labels, n);
    // No superpixel straddles the edge.
    std::vector<int> left(static_cast<std::size_t>(n), 0), right(static_cast<std::size_t>(n), 0);
    for (int y = 0; y < labels.rows; ++y) {
      for (int x = 0; x < labels.cols; ++x)
        (x < 53 ? left : right)[static_cast<std::size_t>(labels.at<int32_t>(y, x))]++;
    }
    int straddling = 0;
    for (int k = 0; k < n; ++k)
      straddling += std::min(left[static_cast<std::size_t>(k)], right[static_cast<std::size_t>(k)]);
    EXPECT_EQ(straddling, 0) << (incremental ? "incremental" : "plain");
  }
}

TEST(Slic, SmallAndDegenerateInputs) {
  Slic slic;
  cv::Mat labels;
  const cv::Mat tiny(5, 7, CV_8UC1, cv::Scalar(10));
  EXPECT_EQ(slic.segment(tiny, labels, true, nullptr), 1);
  EXPECT_EQ(labels.size(), tiny.size());
  const cv::Mat empty;
  EXPECT_EQ(slic.segment(empty, labels, false, nullptr), 0);
  // A large input is capped at max_superpixels seeds.
  SlicConfig c;
  c.max_superpixels = 50;
  Slic capped(c);
  SlicStats st;
  const cv::Mat big = testing::make_texture(400, 128, 60, 2);
  capped.segment(big, labels, &st);
  EXPECT_LE(st.seeds, 60);
  EXPECT_GT(st.step_px, c.superpixel_size_px);
}

}  // namespace
}  // namespace agvslam::dynamic
