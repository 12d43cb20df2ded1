#pragma once
// FNV-1a 64-bit hash (internal): the vocabulary file's checksum and identity. Every step (xor a byte, multiply by
// an odd constant) is a bijection of the state, so two inputs of one length that differ in any one byte always
// hash differently: a single flipped bit or byte in a file is always detected.

#include <cstddef>
#include <cstdint>

namespace agvslam::place::detail {

class Fnv1a64 {
 public:
  void update(const void* data, std::size_t size) {
    const auto* p = static_cast<const uint8_t*>(data);
    uint64_t h = state_;
    for (std::size_t i = 0; i < size; ++i) {
      h ^= p[i];
      h *= 0x100000001b3ULL;
    }
    state_ = h;
  }
  template <class T>
  void update_value(const T& value) {
    update(&value, sizeof(T));
  }
  uint64_t value() const { return state_; }

 private:
  uint64_t state_ = 0xcbf29ce484222325ULL;
};

}  // namespace agvslam::place::detail
