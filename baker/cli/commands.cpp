#include "commands.h"

#include <spdlog/spdlog.h>

namespace spherechain::cli {

void Register(CLI::App& app, Commands* commands) {
  RegisterBake(app, commands);
  RegisterInspect(app, commands);
  RegisterExportDebug(app, commands);
  RegisterPlay(app, commands);
  RegisterValidate(app, commands);
  RegisterEvaluate(app, commands);
  RegisterView(app, commands);
}

int Dispatch(const Commands& commands) {
  for (const auto& [sub, handler] : commands.handlers)
    if (sub->parsed()) return handler();
  return 2;
}

baker::Context MakeLoggingContext() {
  baker::Context ctx;
  ctx.sink = [](baker::Context::Level level, const std::string& m) {
    switch (level) {
      case baker::Context::Level::kDebug: spdlog::debug("{}", m); break;
      case baker::Context::Level::kInfo: spdlog::info("{}", m); break;
      case baker::Context::Level::kWarn: spdlog::warn("{}", m); break;
    }
  };
  return ctx;
}

int Fail(const baker::Error& error) {
  spdlog::error("{}: {}", baker::ToString(error.code), error.message);
  return 1;
}

int Fail(const std::string& message) {
  spdlog::error("{}", message);
  return 1;
}

}  // namespace spherechain::cli
