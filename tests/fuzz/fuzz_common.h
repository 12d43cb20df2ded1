#pragma once
// Shared by the fuzz targets (targets/*.cpp): each defines LLVMFuzzerTestOneInput and feeds the bytes the way the
// product receives them (a file where the API takes a path, a buffer where it takes bytes). An InputError is the
// expected answer to bad input; any other exception escapes and libFuzzer reports it as a crash, as it does for
// a sanitizer finding, a timeout or an allocation over -rss_limit_mb.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "agvslam/core/error.h"

namespace agvslam::fuzz {

// A private scratch folder of this process (several fuzzers may run at once), removed at exit.
inline const std::filesystem::path& scratch_dir() {
  struct Dir {
    std::filesystem::path path;
    Dir() {
      const char* tmp = std::getenv("TMPDIR");
      path = std::filesystem::path(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") /
             ("agvslam_fuzz_" + std::to_string(::getpid()));
      std::filesystem::create_directories(path);
    }
    ~Dir() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  };
  static const Dir dir;
  return dir.path;
}

// Writes bytes to `path` (overwriting it).
inline void write_bytes(const std::filesystem::path& path, const uint8_t* data, std::size_t size) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
}

// The bytes as a file named `name` in the scratch folder; returns its path.
inline std::string as_file(const uint8_t* data, std::size_t size, const std::string& name) {
  const std::filesystem::path path = scratch_dir() / name;
  write_bytes(path, data, size);
  return path.string();
}

// Runs f, accepting an InputError (a parser's answer to bad input) and nothing else.
template <class F>
void expect_input_error_or_success(F&& f) {
  try {
    f();
  } catch (const InputError&) {
  }
}

}  // namespace agvslam::fuzz
