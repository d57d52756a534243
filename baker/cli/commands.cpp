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

std::string RegionLegendLine(const runtime::AssetView& view) {
  if (!view.valid() || !view.asset->regions()) return {};
  std::string s = "regions:";
  const uint32_t n = runtime::RegionCount(view);
  for (uint32_t r = 0; r < n; ++r)
    s += std::string(r ? ", R" : " R") + std::to_string(r) + " " + runtime::RegionName(view, r) +
         (runtime::IsTrunkRegion(view, r) ? " (trunk)" : "");
  return s;
}

std::string RegionPairName(const runtime::AssetView& view, int a, int b) {
  std::string s = "R" + std::to_string(a) + "-R" + std::to_string(b);
  if (view.valid() && view.asset->regions() && a >= 0 && b >= 0)
    s += std::string(" (") + runtime::RegionName(view, uint32_t(a)) + "-" + runtime::RegionName(view, uint32_t(b)) + ")";
  return s;
}

}  // namespace spherechain::cli
