#include "commands.h"

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

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
  spdlog::error("{}: {}", import::ToString(error.code), error.message);
  return 1;
}

int Fail(const std::string& message) {
  spdlog::error("{}", message);
  return 1;
}

namespace {
// `p` absolute with `.`, `..` and symbolic links of its existing part resolved; lexically when that fails.
std::filesystem::path Resolved(const std::string& p) {
  std::error_code ec;
  std::filesystem::path r = std::filesystem::weakly_canonical(std::filesystem::absolute(p, ec), ec);
  return ec ? std::filesystem::path(p).lexically_normal() : r;
}
}  // namespace

std::string OutputPathProblem(const std::string& path) {
  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  if (!dir.empty() && !std::filesystem::is_directory(dir))
    return "cannot write '" + path + "': folder '" + dir.string() + "' does not exist";
  if (std::filesystem::is_directory(path)) return "cannot write '" + path + "': it is a folder";
  return {};
}

int OutputsClash(std::initializer_list<PathArg> outputs, std::initializer_list<PathArg> inputs,
                 const std::vector<std::string>& more_inputs) {
  std::vector<std::pair<const char*, std::filesystem::path>> written;
  for (const PathArg& out : outputs) {
    if (out.path->empty()) continue;
    const std::filesystem::path r = Resolved(*out.path);
    for (const auto& [flag, other] : written)
      if (other == r) {
        spdlog::error("{} and {} both name '{}': one would overwrite the other", flag, out.flag, *out.path);
        return 2;
      }
    auto clash = [&](const char* flag, const std::string& in) {
      if (in.empty() || Resolved(in) != r) return false;
      spdlog::error("{} '{}' is also {}: writing it would destroy what is read", out.flag, *out.path, flag);
      return true;
    };
    for (const PathArg& in : inputs)
      if (clash(in.flag, *in.path)) return 2;
    for (const std::string& in : more_inputs)
      if (clash("an input", in)) return 2;
    written.emplace_back(out.flag, r);
  }
  return 0;
}

}  // namespace spherechain::cli
