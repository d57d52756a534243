// spherechain CLI — subcommand registration and handlers (one file per subcommand).
#pragma once

#include <cmath>
#include <functional>
#include <initializer_list>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json_fwd.hpp>

#include "spherechain/import/file_io.h"
#include "spherechain/import/types.h"
#include "spherechain/playback/animation_source.h"
#include "spherechain/playback/debug_export.h"
#include "spherechain/runtime/asset.h"

namespace spherechain::cli {

/// Every subcommand registers its options and a handler returning the process exit code.
struct Commands {
  std::vector<std::pair<CLI::App*, std::function<int()>>> handlers;
};

void Register(CLI::App& app, Commands* commands);
int Dispatch(const Commands& commands);

void RegisterBake(CLI::App& app, Commands* commands);
void RegisterInspect(CLI::App& app, Commands* commands);
void RegisterExportDebug(CLI::App& app, Commands* commands);
void RegisterPlay(CLI::App& app, Commands* commands);
void RegisterValidate(CLI::App& app, Commands* commands);
void RegisterEvaluate(CLI::App& app, Commands* commands);
void RegisterView(CLI::App& app, Commands* commands);
void RegisterCheck(CLI::App& app, Commands* commands);

/// `j` as text (`indent` < 0: one line). Strings that are not valid UTF-8 (names from a mesh file or an asset
/// are bytes as the file had them) come out with U+FFFD in place of the bad bytes, where nlohmann::json would
/// throw.
std::string JsonText(const nlohmann::json& j, int indent = 2);

/// A import::Context whose log lines go to spdlog.
import::Context MakeLoggingContext();
/// Logs `error` as "error: <code>: <message>" and returns exit code 1.
int Fail(const import::Error& error);
int Fail(const std::string& message);
/// A usage error found after parsing (a value out of range, an output that cannot be written, options that do
/// not go together): logs "error: <message>" and returns exit code 2, as CLI11's own usage errors.
int UsageError(const std::string& message);

/// CLI::Range(lo, hi) that also refuses NaN, which CLI::Range and CLI::PositiveNumber let through (their
/// comparisons are false): "Value nan not in range [lo - hi]" (hi = infinity: "Value 0 is not >= 1"), a usage
/// error (exit 2) found while parsing. `lo_open`: lo itself refused too ("(lo - hi]"). `as_float`: the value
/// checked as the float32 an option of type float holds (1e-50 is 0 there).
CLI::Validator WithinRange(double lo, double hi = HUGE_VAL, bool lo_open = false, bool as_float = false);

/// The most frames --frames and check's --morph-frames take (a usage error past it): playback::kMaxFrames.
inline constexpr double kMaxFrames = playback::kMaxFrames;

using import::OutputPathProblem;  // "cannot write 'p': ..." before the work (import/file_io.h)
using import::PathArg;
/// Exit code 2 after logging import::OutputsClash's message ("error: -o and --report both name 'x'", "... is
/// also an input") when two outputs, or an output and an input, are one file: writing one would destroy the
/// other. 0 when all are distinct. Call it before any output is written; reads no file.
int OutputsClash(std::initializer_list<PathArg> outputs, std::initializer_list<PathArg> inputs,
                 const std::vector<std::string>& more_inputs = {});

/// -q/--quiet: commands print warnings and errors only — no summaries, tables, progress or "wrote" lines
/// (`inspect` still prints the asset: that is what it is asked for; `validate` still prints its findings).
void SetQuiet(bool quiet);
bool Quiet();
/// std::printf to stdout unless -q (Quiet()).
void Out(const char* format, ...) __attribute__((format(printf, 1, 2)));

/// Region names in the tables (playback/debug_export.h).
using playback::RegionLegendLine;
using playback::RegionPairName;

}  // namespace spherechain::cli
