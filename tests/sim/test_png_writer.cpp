// The simulator's PNG writer: every filter stores the pixels exactly (decoded by OpenCV, which the project's
// readers use), 8- and 16-bit, with and without compression; files are written where asked, and bad input or an
// unwritable path gives an error naming it.
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "agvslam/core/error.h"
#include "agvslam/sim/png_writer.h"
#include "agvslam/sim/random.h"

namespace agvslam::sim {
namespace {

// Noise, smooth ramps, flat runs and extremes (0 / max), so every filter's arithmetic wraps somewhere.
cv::Mat test_image(int type, uint64_t seed) {
  cv::Mat m(37, 53, type);
  Rng rng(seed, RngStream::kSensor);
  const double max_value = type == CV_16UC1 ? 65535.0 : 255.0;
  for (int v = 0; v < m.rows; ++v)
    for (int u = 0; u < m.cols; ++u) {
      double x;
      if (v < 10)
        x = rng.uniform(0.0, max_value);  // noise
      else if (v < 20)
        x = (u * 1237.0 + v * 311.0) / (53 * 1237.0) * max_value;  // ramps
      else if (v < 30)
        x = (u / 8) % 2 ? max_value : 0.0;  // runs of extremes
      else
        x = max_value * 0.5;  // flat
      if (type == CV_16UC1)
        m.at<uint16_t>(v, u) = static_cast<uint16_t>(x);
      else
        m.at<uint8_t>(v, u) = static_cast<uint8_t>(x);
    }
  return m;
}

TEST(PngWriter, EveryFilterAndLevelRoundTripsExactly) {
  for (int type : {CV_8UC1, CV_16UC1})
    for (int level : {0, 1, 6})
      for (PngFilter filter :
           {PngFilter::kNone, PngFilter::kSub, PngFilter::kUp, PngFilter::kAverage, PngFilter::kPaeth}) {
        const cv::Mat image = test_image(type, 7 + static_cast<uint64_t>(level));
        PngWriter writer(level);
        const std::vector<uint8_t>& bytes = writer.encode(image, filter);
        const cv::Mat decoded = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
        ASSERT_EQ(decoded.type(), type) << "level " << level << " filter " << static_cast<int>(filter);
        ASSERT_EQ(decoded.size(), image.size());
        EXPECT_EQ(cv::countNonZero(decoded != image), 0) << "level " << level << " filter " << static_cast<int>(filter);
      }
}

TEST(PngWriter, EncodesARegionOfALargerImage) {
  // Rows with a stride larger than the row (a ROI): the writer must follow the stride.
  const cv::Mat big = test_image(CV_16UC1, 3);
  const cv::Mat roi = big(cv::Rect(5, 4, 30, 20));
  PngWriter writer(1);
  const cv::Mat decoded = cv::imdecode(writer.encode(roi, PngFilter::kPaeth), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(decoded.size(), roi.size());
  EXPECT_EQ(cv::countNonZero(decoded != roi), 0);
}

TEST(PngWriter, CompressionShrinksSmoothImages) {
  cv::Mat ramp(100, 200, CV_16UC1);
  for (int v = 0; v < ramp.rows; ++v)
    for (int u = 0; u < ramp.cols; ++u) ramp.at<uint16_t>(v, u) = static_cast<uint16_t>(1000 + 7 * u + 3 * v);
  PngWriter stored(0), compressed(1);
  const std::size_t stored_bytes = stored.encode(ramp, PngFilter::kPaeth).size();
  const std::size_t compressed_bytes = compressed.encode(ramp, PngFilter::kPaeth).size();
  EXPECT_GT(stored_bytes, ramp.total() * 2);
  EXPECT_LT(compressed_bytes * 4, stored_bytes);
}

TEST(PngWriter, WritesTheFileAndRejectsBadInput) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "agvslam_test_png_writer";
  std::filesystem::create_directories(dir);
  const cv::Mat image = test_image(CV_8UC1, 11);
  PngWriter writer(1);
  const std::string path = (dir / "a.png").string();
  writer.write(path, image, PngFilter::kSub);
  const cv::Mat read = cv::imread(path, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(read.size(), image.size());
  EXPECT_EQ(cv::countNonZero(read != image), 0);

  try {
    writer.write((dir / "missing_folder" / "b.png").string(), image, PngFilter::kSub, "--out");
    FAIL() << "expected an error for a path in a missing folder";
  } catch (const InputError& e) {
    EXPECT_EQ(e.source(), "--out");
    EXPECT_NE(std::string(e.what()).find("missing_folder"), std::string::npos) << e.what();
  }
  EXPECT_THROW(writer.encode(cv::Mat(), PngFilter::kSub), InputError);
  EXPECT_THROW(writer.encode(cv::Mat(4, 4, CV_32FC1, cv::Scalar(0)), PngFilter::kSub), InputError);
  EXPECT_THROW(writer.encode(cv::Mat(4, 4, CV_8UC3, cv::Scalar(0)), PngFilter::kSub), InputError);
  EXPECT_THROW(PngWriter(10), InputError);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace agvslam::sim
