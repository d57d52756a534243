#include "commands.h"

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <filesystem>

namespace spherechain::cli {

void Register(CLI::App& app, Commands* commands) {
  RegisterBake(app, commands);
  RegisterInspect(app, commands);
  RegisterExportDebug(app, commands);
  RegisterPlay(app, commands);
  RegisterValidate(app, commands);
  RegisterEvaluate(app, commands);
  RegisterView(app, commands);
  RegisterCheck(app, commands);
}

std::string JsonText(const nlohmann::json& j, int indent) {
  return j.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace);
}

int Dispatch(const Commands& commands) {
  for (const auto& [sub, handler] : commands.handlers)
    if (sub->parsed()) return handler();
  return 2;
}

import::Context MakeLoggingContext() {
  import::Context ctx;
  ctx.sink = [](import::Context::Level level, const std::string& m) {
    switch (level) {
      case import::Context::Level::kDebug: spdlog::debug("{}", m); break;
      case import::Context::Level::kInfo: spdlog::info("{}", m); break;
      case import::Context::Level::kWarn: spdlog::warn("{}", m); break;
    }
  };
  return ctx;
}

namespace {
bool g_quiet = false;
}  // namespace

void SetQuiet(bool quiet) { g_quiet = quiet; }
bool Quiet() { return g_quiet; }

void Out(const char* format, ...) {
  if (g_quiet) return;
  va_list args;
  va_start(args, format);
  std::vprintf(format, args);
  va_end(args);
}

int Fail(const import::Error& error) {
  spdlog::error("{}", import::ToString(error));
  return 1;
}

int Fail(const std::string& message) {
  spdlog::error("{}", message);
  return 1;
}

int UsageError(const std::string& message) {
  spdlog::error("{}", message);
  return 2;
}

CLI::Validator WithinRange(double lo, double hi, bool lo_open, bool as_float) {
  const std::string l = CLI::detail::to_string(lo), h = CLI::detail::to_string(hi);
  const std::string range = std::isinf(hi) ? (lo_open ? "> " : ">= ") + l : (lo_open ? "(" : "[") + l + " - " + h + "]";
  return CLI::Validator(
      [lo, hi, lo_open, as_float, range](std::string& text) -> std::string {
        double value = 0.0;
        if (!CLI::detail::lexical_cast(text, value)) return "Value " + text + " could not be converted";
        if (as_float) value = static_cast<double>(static_cast<float>(value));  // what the option will hold
        if (!((lo_open ? value > lo : value >= lo) && value <= hi))
          return "Value " + text + (std::isinf(hi) ? " is not " : " not in range ") + range +
                 (as_float ? " as a float32" : "");
        return {};
      },
      std::isinf(hi) ? "NUMBER " + range : "FLOAT in " + range);
}

int OutputsClash(std::initializer_list<PathArg> outputs, std::initializer_list<PathArg> inputs,
                 const std::vector<std::string>& more_inputs) {
  const std::string clash = import::OutputsClash(outputs, inputs, more_inputs);
  if (clash.empty()) return 0;
  spdlog::error("{}", clash);
  return 2;
}

}  // namespace spherechain::cli
