#pragma once
// A params/*.yaml file: a map of sections, each a map of settings. Every error is an InputError naming the file,
// the field ("section.key") and what was expected, e.g.
//   "params/stereo.yaml: sgbm.block_size: expected an odd integer in [1, 11], got 'five'"
// Loaders normally go through a params::Table (param_table.h), which calls this; yaml-cpp stays an implementation
// detail of agvslam_core.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace agvslam::params {

class File {
 public:
  // Loads the file. Throws InputError for a missing or unreadable file, a YAML syntax error, or a top level that is
  // not a map. An empty file (or one of comments only) is a file without sections.
  explicit File(const std::string& path);
  ~File();
  File(const File&) = delete;
  File& operator=(const File&) = delete;

  const std::string& path() const;
  // True when the top level has the key, whatever its value (an empty section counts).
  bool has_section(const std::string& section) const;
  // Throws InputError(path, section, "expected a 'section:' section") when has_section() is false.
  void require_section(const std::string& section) const;

  // Throws InputError for a top-level key that is not in `allowed` (the message lists them).
  void check_sections(const std::vector<std::string>& allowed) const;
  // Throws InputError for a key of `section` that is not in `allowed`, or a section that is neither a map nor empty.
  // An absent section passes.
  void check_keys(const std::string& section, const std::vector<std::string>& allowed) const;

  // Overwrites `value` with section.key and returns true when the key is present; returns false and leaves `value`
  // unchanged when it (or its section) is absent. A value that is not a scalar of the type, or a double that is not
  // finite, raises InputError(path, "section.key", "expected " + expectation + ", got '<text>'").
  bool read(const std::string& section, const std::string& key, int& value, const std::string& expectation) const;
  bool read(const std::string& section, const std::string& key, double& value, const std::string& expectation) const;
  bool read(const std::string& section, const std::string& key, bool& value, const std::string& expectation) const;
  bool read(const std::string& section, const std::string& key, uint64_t& value, const std::string& expectation) const;
  bool read(const std::string& section, const std::string& key, std::string& value,
            const std::string& expectation) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace agvslam::params
