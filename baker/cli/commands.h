// spherechain CLI — subcommand registration and handlers (one file per subcommand).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "spherechain/baker/types.h"
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

/// A baker::Context whose log lines go to spdlog.
baker::Context MakeLoggingContext();
/// Logs `error` as "error: <code>: <message>" and returns exit code 1.
int Fail(const baker::Error& error);
int Fail(const std::string& message);

/// "regions: R0 Tail, R1 HindLeg_L, …, R6 trunk (trunk)" for an asset that names its regions (a creature,
/// schema v4); empty for the paper's five (the tables' R0..R4 are documented).
std::string RegionLegendLine(const runtime::AssetView& view);
/// "R1-R2" for a region pair; with the asset's names for a creature: "R1-R2 (HindLeg_L-HindLeg_R)".
std::string RegionPairName(const runtime::AssetView& view, int a, int b);

}  // namespace spherechain::cli
