#include "commands.h"
namespace spherechain::cli {
void RegisterPlay(CLI::App&, Commands*) {}
}  // namespace spherechain::cli
