#pragma once
// Ground-truth readers and error measures for the shared disparity pairs (tests only).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <utility>
#include <vector>

#include "agvslam/stereo/sgbm.h"

namespace agvslam::stereo::testing {

// Portable float map (Middlebury): "Pf", "w h", scale (< 0: little endian), rows bottom to top.
inline cv::Mat read_pfm(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  std::string magic;
  int width = 0, height = 0;
  double scale = 0;
  in >> magic >> width >> height >> scale;
  in.get();  // the single whitespace after the scale
  if (magic != "Pf" || width <= 0 || height <= 0 || scale == 0) return {};
  const bool little_endian = scale < 0;
  cv::Mat out(height, width, CV_32FC1);
  std::vector<unsigned char> row(static_cast<std::size_t>(width) * 4);
  for (int y = height - 1; y >= 0; --y) {
    in.read(reinterpret_cast<char*>(row.data()), static_cast<std::streamsize>(row.size()));
    if (!in) return {};
    for (int x = 0; x < width; ++x) {
      unsigned char b[4];
      std::memcpy(b, &row[static_cast<std::size_t>(x) * 4], 4);
      if (!little_endian) {
        std::swap(b[0], b[3]);
        std::swap(b[1], b[2]);
      }
      float v;
      std::memcpy(&v, b, 4);
      out.at<float>(y, x) = v;
    }
  }
  return out;
}

// KITTI disparity PNG: 16-bit, disparity * 256, 0 = no ground truth.
inline cv::Mat read_kitti_disparity(const std::string& path) {
  const cv::Mat raw = cv::imread(path, cv::IMREAD_ANYDEPTH);
  if (raw.empty() || raw.type() != CV_16UC1) return {};
  cv::Mat out;
  raw.convertTo(out, CV_32F, 1.0 / 256.0);
  return out;
}

struct BadRate {
  double rate = 0;
  int evaluated = 0;
  int estimated = 0;  // evaluated pixels that got a disparity
};

// KITTI D1: a pixel is bad when |error| > 3 px and > 5 % of the true disparity; pixels without an estimate
// count as bad (as in the KITTI devkit, which interpolates; counting them bad is stricter).
inline BadRate kitti_d1(const cv::Mat& estimate_px, const cv::Mat& truth_px) {
  BadRate r;
  int bad = 0;
  for (int y = 0; y < truth_px.rows; ++y) {
    for (int x = 0; x < truth_px.cols; ++x) {
      const float t = truth_px.at<float>(y, x);
      if (!(t > 0)) continue;
      ++r.evaluated;
      const float e = estimate_px.at<float>(y, x);
      if (!(e > 0)) continue;
      ++r.estimated;
      const float err = std::abs(e - t);
      if (err > 3.0f && err > 0.05f * t) ++bad;
    }
  }
  r.rate = r.estimated > 0 ? static_cast<double>(bad) / r.estimated : 1.0;
  return r;
}

// Middlebury bad-2.0 on the non-occluded mask (255), over pixels with an estimate.
inline BadRate middlebury_bad(const cv::Mat& estimate_px, const cv::Mat& truth_px, const cv::Mat& nonocc,
                              float threshold) {
  BadRate r;
  int bad = 0;
  for (int y = 0; y < truth_px.rows; ++y) {
    for (int x = 0; x < truth_px.cols; ++x) {
      const float t = truth_px.at<float>(y, x);
      if (nonocc.at<uint8_t>(y, x) != 255 || !std::isfinite(t)) continue;
      ++r.evaluated;
      const float e = estimate_px.at<float>(y, x);
      if (!(e > 0)) continue;
      ++r.estimated;
      if (std::abs(e - t) > threshold) ++bad;
    }
  }
  r.rate = r.estimated > 0 ? static_cast<double>(bad) / r.estimated : 1.0;
  return r;
}

struct Pair {
  cv::Mat left, right, truth_px, nonocc;
};

inline Pair load_kitti(const std::string& dir) {
  Pair p;
  p.left = cv::imread(dir + "/image_2/000046_10.png", cv::IMREAD_GRAYSCALE);
  p.right = cv::imread(dir + "/image_3/000046_10.png", cv::IMREAD_GRAYSCALE);
  p.truth_px = read_kitti_disparity(dir + "/disp_occ_0/000046_10.png");
  return p;
}

inline Pair load_middlebury(const std::string& dir) {
  Pair p;
  p.left = cv::imread(dir + "/im0.png", cv::IMREAD_GRAYSCALE);
  p.right = cv::imread(dir + "/im1.png", cv::IMREAD_GRAYSCALE);
  p.truth_px = read_pfm(dir + "/disp0GT.pfm");
  p.nonocc = cv::imread(dir + "/mask0nocc.png", cv::IMREAD_GRAYSCALE);
  return p;
}

inline SgbmConfig kitti_config() {
  SgbmConfig c;
  c.num_disparities = 96;  // ground truth reaches 65.7 px
  return c;
}

inline SgbmConfig middlebury_config() {
  SgbmConfig c;
  c.num_disparities = 80;  // ground truth reaches 62.9 px (calib.txt: ndisp 70)
  return c;
}

}  // namespace agvslam::stereo::testing
