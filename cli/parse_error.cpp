#include "cli/parse_error.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <regex>
#include <sstream>
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
    for (int i = 1; i < argc; ++i) {
        std::string arg = argv[i];
        if (arg.rfind("--", 0) != 0) continue;
        arg = arg.substr(0, arg.find('='));
        if (std::find(known.begin(), known.end(), arg) != known.end()) continue;
        if (std::string near = nearestName(arg, known); !near.empty()) return near;
    }
    return "";
}

// "1048576.000000" -> "1048576", "0.500000" -> "0.5".
std::string shortNumber(const std::string& text) {
    char buf[48];
    double v = std::atof(text.c_str());
    if (v == std::floor(v) && std::fabs(v) < 1e15)
        std::snprintf(buf, sizeof buf, "%.0f", v);
    else
        std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

}  // namespace

std::string nearestName(const std::string& word, const std::vector<std::string>& known) {
    std::string best;
    size_t bestDistance = 3;  // at most two edits away
    for (const std::string& k : known) {
        size_t d = editDistance(word, k);
        if (d < bestDistance || (k.rfind(word, 0) == 0 && best.empty() && !word.empty())) {
            bestDistance = std::min(d, bestDistance);
            best = k;
        }
    }
    return best;
}

std::string plainValueError(const CLI::App& cmd, const std::string& message) {
    std::smatch m;
    static const std::regex convert("Could not convert: (-[-\\w]+) = (.*)");
    if (std::regex_match(message, m, convert)) {
        std::string flag = m[1], value = m[2], kind = "not a number";
        for (const CLI::Option* opt : cmd.get_options())
            for (const std::string& name : opt->get_lnames())
                if ("--" + name == flag) {
                    std::string type = opt->get_type_name();
                    if (type == "INT" || type == "UINT") kind = "not a whole number";
                }
        return flag + " " + value + ": " + kind;
    }
    static const std::regex range("(-[-\\w]+): Value (.*) not in range (\\S+) to (\\S+)");
    if (std::regex_match(message, m, range)) {
        const std::string value = m[2];
        char* end = nullptr;
        std::strtod(value.c_str(), &end);
        bool number = !value.empty() && end && *end == 0;
        return std::string(m[1]) + " " + value + ": " +
               (number ? "must be in " : "not a number; expected ") + shortNumber(m[3]) + ".." +
               shortNumber(m[4]);
    }
    static const std::regex member("(-[-\\w]+): (.*) not in \\{(.*)\\}");
    if (std::regex_match(message, m, member)) {
        std::string choices = m[3];
        std::replace(choices.begin(), choices.end(), ',', ' ');
        std::string list;
        std::istringstream words(choices);
        for (std::string w; words >> w;) list += (list.empty() ? "" : ", ") + w;
        return std::string(m[1]) + " " + std::string(m[2]) + ": must be one of " + list;
    }
    return message;
}

int reportParseError(const CLI::App& app, const CLI::ParseError& error, const char* prog, int argc,
                     char** argv) {
    if (error.get_exit_code() == 0) return app.exit(error);  // --help, --version
    const CLI::App* cmd = addressed(app, argc, argv);
    std::string help = prog;
    if (cmd != &app) help += " " + cmd->get_name();
    std::string hint = nearestFlag(*cmd, argc, argv);
    std::fprintf(stderr, "%s: %s%s (see %s --help)\n", prog,
                 plainValueError(*cmd, error.what()).c_str(),
                 hint.empty() ? "" : (" (did you mean " + hint + "?)").c_str(), help.c_str());
    return kUsageError;
}

}  // namespace rt::cli
