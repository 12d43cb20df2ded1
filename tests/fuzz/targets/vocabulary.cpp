// The vocabulary file (params/vocabulary/*.bin, agvslam-vocab --out), read with Vocabulary::deserialize as load()
// does. The FNV-1a checksum is recomputed over the mutated bytes first, so that the fuzzer reaches the tree checks
// behind it (a wrong checksum alone is refused at once).
#include <cstring>
#include <string>

#include "../../src/place/hash.h"
#include "agvslam/place/vocabulary.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  constexpr std::size_t kHeaderBytes = 128, kChecksumOffset = 96;  // vocabulary.h's layout
  std::string bytes(reinterpret_cast<const char*>(data), size);
  if (size >= kHeaderBytes) {
    auto* b = reinterpret_cast<uint8_t*>(bytes.data());
    agvslam::place::detail::Fnv1a64 h;
    h.update(b, kChecksumOffset);
    h.update(b + kChecksumOffset + 8, size - kChecksumOffset - 8);
    const uint64_t checksum = h.value();
    std::memcpy(b + kChecksumOffset, &checksum, 8);
  }
  agvslam::fuzz::expect_input_error_or_success([&] {
    const agvslam::place::Vocabulary v = agvslam::place::Vocabulary::deserialize(bytes.data(), bytes.size(), "fuzz");
    // Lookups walk the tree the file described: descriptors of every bit pattern class.
    cv::Mat descriptors(4, 32, CV_8UC1);
    for (int r = 0; r < descriptors.rows; ++r) descriptors.row(r).setTo(cv::Scalar(r * 85));
    agvslam::place::BowVector bow;
    agvslam::place::FeatureVector features;
    v.transform(descriptors, bow, features, 2);
    v.serialize();
  });
  return 0;
}
