// rtlab — how every front end reports a bad command line: one line naming the flag, the nearest
// flag the command does know (for a typo), the command's --help, and exit status 1.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

namespace rt::cli {

// Exit status of every usage error (bad flag, bad value, unknown command), as the README says.
constexpr int kUsageError = 1;

// Prints `prog: <reason> [(did you mean --x?)] (see <prog [sub]> --help)` on stderr and returns
// kUsageError; for --help (exit code 0) prints the help and returns 0.
int reportParseError(const CLI::App& app, const CLI::ParseError& error, const char* prog, int argc,
                     char** argv);

// The name in `known` at most two edits from `word` (or that it begins), nearest first; empty
// when none is close. "rendr" -> "render".
std::string nearestName(const std::string& word, const std::vector<std::string>& known);

// CLI11's wording of a bad value, in rtlab's: "--bounces four: not a whole number" for
// "Could not convert: --bounces = four", "--pipeline foo: must be one of cpu, mega" for
// "--pipeline: foo not in {cpu,mega}". Other messages pass unchanged.
std::string plainValueError(const CLI::App& cmd, const std::string& message);

}  // namespace rt::cli
