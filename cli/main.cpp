// spherechain — the command-line tool: bake, inspect, export-debug, play, validate, evaluate, view, check.
#include <csignal>
#include <exception>

#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "commands.h"
#include "spherechain/import/file_io.h"

namespace {
// An interrupted command (Ctrl-C, a build system's timeout, a closed terminal) removes the hidden temporaries of
// the outputs it had not yet renamed into place, then ends by the same signal: the shell and a build system see
// the interruption (exit 128 + N), and every output path keeps what it held.
extern "C" void EndOnSignal(int sig) {
  spherechain::import::RemoveTemporariesOnSignal();
  std::raise(sig);  // SA_RESETHAND: the default action, taken once this handler returns
}

void RemoveOutputsOnInterrupt() {
  constexpr int kEnding[] = {SIGINT, SIGTERM, SIGHUP, SIGQUIT};  // RemoveTemporariesOnSignal's (file_io.h)
  struct sigaction action = {};
  action.sa_handler = EndOnSignal;
  sigemptyset(&action.sa_mask);  // the others wait while one is handled: a Ctrl-C then a Ctrl-\ run it once
  for (const int sig : kEnding) sigaddset(&action.sa_mask, sig);
  action.sa_flags = SA_RESETHAND;
  for (const int sig : kEnding) {
    struct sigaction old = {};
    // A signal the caller set to be ignored (nohup's SIGHUP, a background job's SIGINT) stays ignored.
    if (sigaction(sig, nullptr, &old) == 0 && old.sa_handler != SIG_IGN) sigaction(sig, &action, nullptr);
  }
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"spherechain — sphere-chain self-collision assets for animated characters\n"
               "(Madera, Ayala, Moo-Mena 2015: Self-collision Detection using Sphere Chains)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "spherechain " SPHERECHAIN_VERSION);  // the CMake project's version
  bool verbose = false, quiet = false;
  app.add_flag("-v,--verbose", verbose, "Log every stage in detail");
  app.add_flag("-q,--quiet", quiet, "Log warnings and errors only");
  spherechain::cli::Commands commands;
  spherechain::cli::Register(app, &commands);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // Usage errors exit 2 (as `check` documents for bad input); --help and --version 0.
    return app.exit(e) == 0 ? 0 : 2;
  }
  // Messages (info, warnings, errors) on stderr, as docs/cli.md promises: stdout carries only what a
  // command produces (tables, summaries, JSON), so a pipeline can redirect one without the other.
  spdlog::set_default_logger(spdlog::stderr_color_mt("spherechain"));
  spdlog::set_pattern("%^%l%$: %v");
  spdlog::set_level(verbose ? spdlog::level::debug : quiet ? spdlog::level::warn : spdlog::level::info);
  spherechain::cli::SetQuiet(quiet);
  RemoveOutputsOnInterrupt();
  // A library call that throws (std::filesystem on a folder it may not read, an allocation) ends the
  // command with its message and exit 1, not with std::terminate; outputs are written atomically, so
  // none is left half-written.
  try {
    return spherechain::cli::Dispatch(commands);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
}
