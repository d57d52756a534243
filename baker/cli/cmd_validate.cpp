#include "commands.h"
namespace spherechain::cli {
void RegisterValidate(CLI::App&, Commands*) {}
}  // namespace spherechain::cli
