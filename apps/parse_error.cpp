#include "apps/parse_error.h"

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

namespace rt::cli {
namespace {

size_t editDistance(const std::string& a, const std::string& b) {
    std::vector<size_t> row(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (size_t i = 1; i <= a.size(); ++i) {
        size_t diagonal = row[0];
        row[0] = i;
        for (size_t j = 1; j <= b.size(); ++j) {
            size_t above = row[j];
            row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] != b[j - 1])});
            diagonal = above;
        }
    }
    return row[b.size()];
}

// The command the user addressed: the subcommand named on the command line, else the app.
const CLI::App* addressed(const CLI::App& app, int argc, char** argv) {
    for (const CLI::App* sub : app.get_subcommands({}))
        for (int i = 1; i < argc; ++i)
            if (sub->get_name() == argv[i]) return sub;
    return &app;
}

// "--bounce" -> "--bounces": the known long flag nearest to an unknown one, if any is close.
std::string nearestFlag(const CLI::App& cmd, int argc, char** argv) {
    std::vector<std::string> known;
    for (const CLI::Option* opt : cmd.get_options())
        for (const std::string& name : opt->get_lnames()) known.push_back("--" + name);
    std::string best;
    size_t bestDistance = 3;  // at most two edits away
    for (int i = 1; i < argc; ++i) {
        std::string arg = argv[i];
        if (arg.rfind("--", 0) != 0) continue;
        arg = arg.substr(0, arg.find('='));
        if (std::find(known.begin(), known.end(), arg) != known.end()) continue;
        for (const std::string& k : known) {
            size_t d = editDistance(arg, k);
            if (d < bestDistance || (k.rfind(arg, 0) == 0 && best.empty())) {
                bestDistance = std::min(d, bestDistance);
                best = k;
            }
        }
    }
    return best;
}

}  // namespace

int reportParseError(const CLI::App& app, const CLI::ParseError& error, const char* prog, int argc,
                     char** argv) {
    if (error.get_exit_code() == 0) return app.exit(error);  // --help, --version
    const CLI::App* cmd = addressed(app, argc, argv);
    std::string help = prog;
    if (cmd != &app) help += " " + cmd->get_name();
    std::string hint = nearestFlag(*cmd, argc, argv);
    std::fprintf(stderr, "%s: %s%s (see %s --help)\n", prog, error.what(),
                 hint.empty() ? "" : (" (did you mean " + hint + "?)").c_str(), help.c_str());
    return kUsageError;
}

}  // namespace rt::cli
