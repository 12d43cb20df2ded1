#pragma once
// agvslamd's logging: spdlog to stderr (the journal, under systemd) and optionally to a file that SIGHUP reopens
// (logrotate moves the file, sends HUP, the daemon continues in a new file of the same name).

#include <spdlog/details/file_helper.h>
#include <spdlog/sinks/base_sink.h>
#include <memory>
#include <mutex>
#include <string>

namespace agvslam::daemon {

// A file sink whose file can be closed and opened again by name (appending).
class ReopenableFileSink final : public spdlog::sinks::base_sink<std::mutex> {
 public:
  // Throws InputError(source, field, ...) when the file cannot be opened.
  ReopenableFileSink(const std::string& path, const std::string& source, const std::string& field);
  // Closes the file and opens `path` again (a new file if it was moved away). Returns false (and keeps logging
  // to stderr only) when it cannot.
  bool reopen();
  const std::string& path() const { return path_; }

 protected:
  void sink_it_(const spdlog::details::log_msg& msg) override;
  void flush_() override;

 private:
  std::string path_;
  spdlog::details::file_helper file_;
  bool open_ = false;
};

// Installs the default logger "agvslamd": stderr, plus the file when `file` is not empty. level: trace, debug,
// info, warn, error (InputError(source, "log.level", ...) otherwise). Returns the file sink (null without).
std::shared_ptr<ReopenableFileSink> setup_logging(const std::string& file, const std::string& level,
                                                  const std::string& source);

}  // namespace agvslam::daemon
