// rtlab — command-line front end: `rtlab render`, `rtlab devices`, `rtlab sweep`.
// Every failure, a usage error included, ends in one line on stderr ("rtlab: <reason>") and exit
// status 1.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>

#include "apps/commands.h"
#include "bench/watchdog.h"
#include "cli/parse_error.h"
#include "core/cl_runtime.h"
#include "core/error.h"
#include "core/version.h"
#include "pipelines/registry.h"

namespace {

int mainCommand(int argc, char** argv) {
    CLI::App app{
        "rtlab: Whitted ray tracing on OpenCL, pipeline against pipeline.\n"
        "Renders scenes with a double-precision CPU reference and every registered\n"
        "pipeline, and measures them:\n" +
        rt::pipelineRegistry().help()};
    app.set_version_flag("--version", std::string("rtlab ") + RTLAB_COMMIT,
                         "Print the commit this binary was built from and exit");
    app.require_subcommand(1);
    rt::cli::addRender(app);
    rt::cli::addDevices(app);
    rt::cli::addCompare(app);
    rt::cli::addSweep(app);
    rt::cli::addLists(app);
    rt::cli::addPredict(app);
    std::string names;
    bool known = false;
    for (const CLI::App* sub : app.get_subcommands({})) {
        names += (names.empty() ? "" : ", ") + sub->get_name();
        known |= argc > 1 && sub->get_name() == argv[1];
    }
    if (argc > 1 && argv[1][0] != '-' && !known) {
        std::vector<std::string> commands;
        for (const CLI::App* sub : app.get_subcommands({})) commands.push_back(sub->get_name());
        std::string near = rt::cli::nearestName(argv[1], commands);
        std::fprintf(stderr, "rtlab: unknown command '%s'%s (commands: %s; see rtlab --help)\n",
                     argv[1], near.empty() ? "" : (" (did you mean " + near + "?)").c_str(),
                     names.c_str());
        return rt::cli::kUsageError;
    }
    try {
        app.parse(argc, argv);
        return rt::cli::run(app);
    } catch (const CLI::ParseError& e) {
        return rt::cli::reportParseError(app, e, "rtlab", argc, argv);
    } catch (const rt::Error& e) {
        std::fprintf(stderr, "rtlab: %s\n", e.what());
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "rtlab: unexpected error: %s\n", e.what());
        return 1;
    }
}

}  // namespace

int main(int argc, char** argv) {
    // On a terminal a cold first run says what it compiles (seconds each on a fresh machine).
    rt::ClContext::announceBuilds(isatty(STDERR_FILENO) == 1);
    int status = mainCommand(argc, argv);
    // A sweep left a thread stuck in the driver (a cell timed out): exit without destructors
    // or exit handlers, which could wait on it.
    if (rt::bench::workAbandoned()) {
        std::fflush(nullptr);
        std::_Exit(status);
    }
    return status;
}
