// rtlab sweep: filled in by the benchmark issue.
#include "apps/commands.h"

namespace rt::cli {

void addSweep(CLI::App& app) { (void)app; }
int runSweepCommand() { return 0; }

}  // namespace rt::cli
