// rtlab — the one exception type. Every user-facing failure (bad scene, bad flag, device limit,
// OpenCL error) becomes an rt::Error whose what() is the single line printed before exiting 1.
// It also carries what kind of failure it is, set where it is thrown, so that sweeps and charts
// classify failures from that kind and never by reading the English message.
#pragma once

#include <stdexcept>
#include <string>

namespace rt {

// The failure kinds a sweep row records ("failure"); the names are the JSON contract.
enum class FailureKind {
    None,           // ""              the cell ran
    PrivateTree,    // "private_tree"  private ray storage over the per-work-item limit
    TreeRow,        // "tree_row"      one row of a global ray tree over max allocation or budget
    OutOfMemory,    // "out_of_memory" a device (or host) allocation failed
    OpenCl,         // "opencl"        any other OpenCL error
    InvalidOption,  // "invalid_option"
    Skipped,        // "skipped"       not run (stop-after-failure)
    Timeout,        // "timeout"       did not finish within the cell time limit
    Other,          // "other"
};

inline const char* failureKindName(FailureKind k) {
    switch (k) {
        case FailureKind::None:
            return "";
        case FailureKind::PrivateTree:
            return "private_tree";
        case FailureKind::TreeRow:
            return "tree_row";
        case FailureKind::OutOfMemory:
            return "out_of_memory";
        case FailureKind::OpenCl:
            return "opencl";
        case FailureKind::InvalidOption:
            return "invalid_option";
        case FailureKind::Skipped:
            return "skipped";
        case FailureKind::Timeout:
            return "timeout";
        case FailureKind::Other:
            return "other";
    }
    return "other";
}

class Error : public std::runtime_error {
  public:
    explicit Error(const std::string& message, FailureKind kind = FailureKind::Other)
        : std::runtime_error(message), kind_(kind) {}
    FailureKind kind() const { return kind_; }

  private:
    FailureKind kind_;
};

}  // namespace rt
