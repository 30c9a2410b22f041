// rtlab tests — a sweep file's text run on the test device, its rows in cell order.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench/sweep_config.h"
#include "bench/sweep_runner.h"
#include "test_device.h"

namespace rt::test {

// The rows of sweep text `text` (named `name` in its meta), run on device(); its summary in
// *summary where asked.
inline std::vector<nlohmann::json> sweepRows(const std::string& text, const std::string& name,
                                             bench::SweepSummary* summary = nullptr) {
    const bench::SweepConfig config = bench::parseSweep(text, name);
    bench::SweepRunOptions o;
    o.device = std::to_string(device().device().index);
    std::vector<nlohmann::json> rows;
    const bench::SweepSummary s = bench::runSweep(
        config, o, nullptr, [&](const nlohmann::json& row, const Image*) { rows.push_back(row); });
    if (summary) *summary = s;
    return rows;
}

}  // namespace rt::test
