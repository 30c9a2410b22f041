// rtlab — the one exception type. Every user-facing failure (bad scene, bad flag, device limit,
// OpenCL error) becomes an rt::Error whose what() is the single line printed before exiting 1.
#pragma once

#include <stdexcept>
#include <string>

namespace rt {

class Error : public std::runtime_error {
public:
    explicit Error(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace rt
