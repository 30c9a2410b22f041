// rtlab tests — the name of a parameterised test case that runs a command line: its index and
// the first 60 characters of its arguments, every other character made an underscore, so that a
// failing case names the command it ran.
#pragma once

#include <gtest/gtest.h>

#include <cctype>
#include <string>

namespace rt::test {

template <class Case>
std::string commandCaseName(const ::testing::TestParamInfo<Case>& info) {
    std::string name = std::to_string(info.index);
    for (char c : std::string(info.param.args).substr(0, 60))
        name += std::isalnum((unsigned char)c) ? c : '_';
    return name;
}

}  // namespace rt::test
