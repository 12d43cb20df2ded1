#include "agvslam/daemon/log_setup.h"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "agvslam/core/error.h"

namespace agvslam::daemon {

ReopenableFileSink::ReopenableFileSink(const std::string& path, const std::string& source, const std::string& field)
    : path_(path) {
  try {
    file_.open(path_, /*truncate=*/false);
    open_ = true;
  } catch (const spdlog::spdlog_ex& e) {
    throw InputError(source, field, "expected a writable log file: " + std::string(e.what()));
  }
}

bool ReopenableFileSink::reopen() {
  std::lock_guard<std::mutex> lock(mutex_);
  file_.close();
  open_ = false;
  try {
    file_.open(path_, /*truncate=*/false);
    open_ = true;
  } catch (const spdlog::spdlog_ex&) {
    return false;
  }
  return true;
}

void ReopenableFileSink::sink_it_(const spdlog::details::log_msg& msg) {
  if (!open_) return;
  spdlog::memory_buf_t formatted;
  formatter_->format(msg, formatted);
  file_.write(formatted);
}

void ReopenableFileSink::flush_() {
  if (open_) file_.flush();
}

std::shared_ptr<ReopenableFileSink> setup_logging(const std::string& file, const std::string& level,
                                                  const std::string& source) {
  const spdlog::level::level_enum lvl = spdlog::level::from_str(level);
  if (lvl == spdlog::level::off && level != "off") {
    throw InputError(source, "log.level", "expected trace, debug, info, warn or error");
  }
  std::vector<spdlog::sink_ptr> sinks;
  sinks.push_back(std::make_shared<spdlog::sinks::stderr_color_sink_mt>());
  std::shared_ptr<ReopenableFileSink> file_sink;
  if (!file.empty()) {
    file_sink = std::make_shared<ReopenableFileSink>(file, source, "log.file");
    sinks.push_back(file_sink);
  }
  auto logger = std::make_shared<spdlog::logger>("agvslamd", sinks.begin(), sinks.end());
  logger->set_level(lvl);
  logger->flush_on(spdlog::level::info);  // the journal and the file see each line at once (a few lines a second)
  spdlog::set_default_logger(logger);
  return file_sink;
}

}  // namespace agvslam::daemon
