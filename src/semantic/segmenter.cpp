#include "agvslam/semantic/segmenter.h"

#include <algorithm>
#include <filesystem>
#include <opencv2/dnn.hpp>
#include <opencv2/imgproc.hpp>
#include <regex>

#include "agvslam/core/error.h"

namespace agvslam::semantic {

struct Segmenter::Net {
  cv::dnn::Net net;
};

namespace {

// OpenCV's importer reports a node it cannot handle as "Node [Type@domain]:(name) parse error: ...".
std::string describe_import_error(const std::string& what) {
  static const std::regex node(R"(Node \[([^@\]]+)@?[^\]]*\]:\(([^)]*)\))");
  std::smatch m;
  if (std::regex_search(what, m, node)) {
    return "expected nodes OpenCV's ONNX importer supports, found node '" + m[2].str() + "' of type " + m[1].str() +
           " (export at opset 10 without Identity nodes, or rewrite them with src/semantic/training/repair_onnx.py): " +
           what;
  }
  return "expected an ONNX model OpenCV can read (the file may be truncated or not ONNX): " + what;
}

std::string shape_text(const cv::Mat& m) {
  std::string s;
  for (int i = 0; i < m.dims; ++i) s += (i ? "x" : "") + std::to_string(m.size[i]);
  return s;
}

}  // namespace

Segmenter::Segmenter(const ModelConfig& config) : config_(config), net_(std::make_unique<Net>()) {
  config_.validate("semantic model settings");
  const std::string& path = config_.path;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw InputError(path, "model", "expected an ONNX model file (model.path in params/semantic.yaml), found none");
  }
  try {
    net_->net = cv::dnn::readNetFromONNX(path);
  } catch (const cv::Exception& e) {
    throw InputError(path, "model", describe_import_error(e.what()));
  }
  if (net_->net.empty()) throw InputError(path, "model", "expected an ONNX model with layers, OpenCV read none");
  net_->net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  net_->net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);

  const std::string input = std::to_string(config_.input_channels) + "x" + std::to_string(config_.input_height) + "x" +
                            std::to_string(config_.input_width);
  cv::Mat out;
  try {
    out = scores(cv::Mat(config_.input_height, config_.input_width, CV_8UC1, cv::Scalar(0)));
  } catch (const cv::Exception& e) {
    throw InputError(path, "model input",
                     "expected a network that accepts a 1x" + input +
                         " image (model.input_channels/input_height/input_width in params/semantic.yaml): " + e.what());
  }
  if (out.dims != 4 || out.size[0] != 1 || out.size[1] < 2) {
    throw InputError(path, "model output", "expected a 1xCxHxW score map with C >= 2 classes, got " + shape_text(out));
  }
  class_count_ = out.size[1];
  for (int id : config_.movable_ids()) {
    if (id >= class_count_) {
      throw InputError(
          path, "model output",
          "expected class scores for every movable class (model.movable_classes: " + config_.movable_classes +
              "), the network gives " + std::to_string(class_count_) + " classes");
    }
  }
}

Segmenter::~Segmenter() = default;

cv::Mat Segmenter::blob(const cv::Mat& grey) const {
  CV_Assert(grey.type() == CV_8UC1 && !grey.empty());
  cv::Mat resized;
  const cv::Size input(config_.input_width, config_.input_height);
  if (grey.size() == input) {
    resized = grey;
  } else {
    cv::resize(grey, resized, input, 0, 0, cv::INTER_AREA);
  }
  cv::Mat image = resized;
  if (config_.input_channels == 3) cv::cvtColor(resized, image, cv::COLOR_GRAY2BGR);
  // blobFromImage computes (pixel - mean) * scale, the normalisation the network was trained with.
  return cv::dnn::blobFromImage(image, config_.scale, input, cv::Scalar::all(config_.mean), false, false, CV_32F);
}

cv::Mat Segmenter::scores(const cv::Mat& grey) {
  net_->net.setInput(blob(grey));
  return net_->net.forward().clone();
}

cv::Mat Segmenter::segment(const cv::Mat& grey) {
  const cv::Mat out = scores(grey);
  const int classes = out.size[1], h = out.size[2], w = out.size[3];
  // Bilinear upsampling of each class's scores (half-pixel centres, as in training), then the best class.
  cv::Mat best_score(grey.size(), CV_32F, cv::Scalar(-1e30f));
  cv::Mat labels(grey.size(), CV_8UC1, cv::Scalar(0));
  cv::Mat up;
  for (int c = 0; c < classes; ++c) {
    const cv::Mat plane(h, w, CV_32F, const_cast<float*>(out.ptr<float>(0, c)));
    cv::resize(plane, up, grey.size(), 0, 0, cv::INTER_LINEAR);
    for (int y = 0; y < grey.rows; ++y) {
      const float* s = up.ptr<float>(y);
      float* b = best_score.ptr<float>(y);
      uint8_t* l = labels.ptr<uint8_t>(y);
      for (int x = 0; x < grey.cols; ++x) {
        if (s[x] > b[x]) {
          b[x] = s[x];
          l[x] = static_cast<uint8_t>(std::min(c, 255));
        }
      }
    }
  }
  return labels;
}

}  // namespace agvslam::semantic
