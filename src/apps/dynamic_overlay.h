#pragma once
// The images agvslam-dynamic writes: masks and ROI outlines as PNGs, and the four-panel overlay (the paper's Figs. 3,
// 5, 7 and 8; the panels are described at the top of agvslam_dynamic.cpp).

#include <cstddef>
#include <opencv2/core.hpp>
#include <string>

#include "agvslam/dynamic/detector.h"
#include "agvslam/stereo/sgbm.h"

namespace agvslam::apps::dynamic_tool {

// NNNNNN.png for frame i.
std::string frame_name(std::size_t i);

// Writes image to path (PNG, fast compression); an InputError naming --out where it cannot.
void write_png(const std::string& path, const cv::Mat& image);

// The four panels of frame r, 2 x 2: (a) SGBM disparity of the whole frame (computed here with sgbm, for display
// only), (b) tracks and ROIs, (c) superpixels and boundaries or ROI disparity and outlines, (d) the mask against
// gt_mask (may be empty).
cv::Mat compose_overlay(const cv::Mat& left, const cv::Mat& right, const agvslam::dynamic::DetectorResult& r,
                        const cv::Mat& gt_mask, agvslam::stereo::StereoSgbm& sgbm);

}  // namespace agvslam::apps::dynamic_tool
