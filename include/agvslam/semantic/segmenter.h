#pragma once
// The segmentation network: any PSPNet-style ONNX model (one image in, per-class scores out at any resolution)
// run with OpenCV's DNN module on the CPU. The model file, its input size and normalisation come from
// params/semantic.yaml (ModelConfig), so another network (e.g. one trained on Cityscapes) drops in with its own
// input size, mean/scale, channels and movable class ids.

#include <memory>
#include <opencv2/core.hpp>
#include <string>

#include "agvslam/semantic/semantic_config.h"

namespace agvslam::semantic {

class Segmenter {
 public:
  // Loads and checks the model: one forward pass on a blank input of the configured size must give a 1 x C x h x w
  // score map with C > every movable class id. Throws InputError naming the model file for a missing or
  // unreadable file, a file OpenCV cannot parse (truncated, not ONNX), a node OpenCV cannot import (the message
  // names the node and its type), or an input/output shape that does not fit the configuration.
  explicit Segmenter(const ModelConfig& config);
  ~Segmenter();
  Segmenter(const Segmenter&) = delete;
  Segmenter& operator=(const Segmenter&) = delete;

  // Class id per pixel (CV_8UC1, the size of `grey`) of a CV_8UC1 image.
  cv::Mat segment(const cv::Mat& grey);
  // The network's raw scores for `grey` (CV_32F, 1 x C x h x w).
  cv::Mat scores(const cv::Mat& grey);

  int class_count() const { return class_count_; }
  const ModelConfig& config() const { return config_; }

 private:
  cv::Mat blob(const cv::Mat& grey) const;

  ModelConfig config_;
  struct Net;
  std::unique_ptr<Net> net_;
  int class_count_ = 0;
};

}  // namespace agvslam::semantic
