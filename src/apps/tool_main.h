#pragma once
// The end of every tool's main(): parse the command line, run, and turn the outcome into the exit status the tools
// document: 0 done (also --help), 2 a bad option or input (CLI11's parse errors; agvslam::InputError, whose message
// names the option, file or field and what was expected; an exception the tool's `is_bad_input` accepts, such as a
// camera that refuses the configuration), 1 any other failure. Errors go to the log.

#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include <exception>
#include <utility>

#include "agvslam/core/error.h"

namespace agvslam::apps {

template <class Run, class IsBadInput>
int parse_and_run(CLI::App& app, int argc, char** argv, Run&& run, IsBadInput&& is_bad_input) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    return run();
  } catch (const InputError& e) {
    spdlog::error("{}", e.what());
    return 2;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return is_bad_input(e) ? 2 : 1;
  }
}

template <class Run>
int parse_and_run(CLI::App& app, int argc, char** argv, Run&& run) {
  return parse_and_run(app, argc, argv, std::forward<Run>(run), [](const std::exception&) { return false; });
}

}  // namespace agvslam::apps
