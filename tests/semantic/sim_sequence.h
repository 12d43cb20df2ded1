#pragma once
// Frames of a simulator scenario for the semantic tests, with the class labels the network would give taken from
// the ground truth: the actors' pixels (instances) are class 5 (person) or 6 (forklift), everything else 0.

#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <string>

#include "agvslam/sim/simulator.h"

namespace agvslam::semantic::test {

class SimSequence {
 public:
  explicit SimSequence(const std::string& scenario, uint64_t seed = 1) {
    sim::ScenarioOptions options;
    options.name = scenario;
    options.seed = seed;
    simulator_ = std::make_unique<sim::Simulator>(sim::SimConfig{}, options);
  }
  // Rendered once, kept.
  const sim::SimFrame& frame(int i) {
    auto it = frames_.find(i);
    if (it == frames_.end()) {
      it = frames_.emplace(i, sim::SimFrame{}).first;
      simulator_->render_frame(i, it->second, 2);
    }
    return it->second;
  }
  // Class ids from the ground truth (5 person, 6 forklift, 7 AGV, 0 elsewhere).
  cv::Mat labels(int i) {
    const sim::SimFrame& f = frame(i);
    cv::Mat out = cv::Mat::zeros(f.instances.size(), CV_8UC1);
    for (const sim::VisibleObject& o : f.objects) {
      const int cls = o.cls == sim::ActorClass::kPerson ? 5 : o.cls == sim::ActorClass::kForklift ? 6 : 7;
      out.setTo(cls, f.instances == o.id);
    }
    return out;
  }
  const sim::Simulator& simulator() const { return *simulator_; }

 private:
  std::unique_ptr<sim::Simulator> simulator_;
  std::map<int, sim::SimFrame> frames_;
};

}  // namespace agvslam::semantic::test
