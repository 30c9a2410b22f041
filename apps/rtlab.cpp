// rtlab — command-line front end: `rtlab render`, `rtlab devices`, `rtlab sweep`.
// Every failure ends in one line on stderr ("rtlab: <reason>") and exit status 1; CLI11 usage
// errors exit with its own code (106 etc.) after naming the flag.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <iostream>
#include <string>

#include "apps/commands.h"
#include "core/error.h"
#include "pipelines/registry.h"

int main(int argc, char** argv) {
    CLI::App app{"rtlab: Whitted ray tracing on OpenCL, pipeline against pipeline.\n"
                 "Renders scenes with a double-precision CPU reference and every registered\n"
                 "pipeline, and measures them:\n" +
                 rt::pipelineRegistry().help()};
    app.require_subcommand(1);
    rt::cli::addRender(app);
    rt::cli::addDevices(app);
    rt::cli::addCompare(app);
    rt::cli::addSweep(app);
    std::string names;
    bool known = false;
    for (const CLI::App* sub : app.get_subcommands({})) {
        names += (names.empty() ? "" : ", ") + sub->get_name();
        known |= argc > 1 && sub->get_name() == argv[1];
    }
    if (argc > 1 && argv[1][0] != '-' && !known) {
        std::fprintf(stderr, "rtlab: unknown command '%s' (commands: %s; see rtlab --help)\n",
                     argv[1], names.c_str());
        return 2;
    }
    try {
        app.parse(argc, argv);
        return rt::cli::run(app);
    } catch (const CLI::ParseError& e) {
        if (e.get_exit_code() == 0) return app.exit(e);  // --help
        std::fprintf(stderr, "rtlab: %s (see rtlab --help)\n", e.what());
        return e.get_exit_code();
    } catch (const rt::Error& e) {
        std::fprintf(stderr, "rtlab: %s\n", e.what());
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "rtlab: unexpected error: %s\n", e.what());
        return 1;
    }
}
