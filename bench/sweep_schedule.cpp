// rtlab bench — work units, shards and device lists of a sweep (see sweep_schedule.h).
#include "bench/sweep_schedule.h"

#include <cctype>
#include <map>

#include "core/error.h"

namespace rt::bench {

Shard parseShard(const std::string& spec) {
    auto bad = [&](const std::string& why) {
        return Error("--shard " + spec + ": " + why + " (expected i/N with 0 <= i < N, e.g. 0/4)");
    };
    size_t slash = spec.find('/');
    if (slash == std::string::npos) throw bad("no '/'");
    auto number = [&](const std::string& s) {
        if (s.empty() || s.size() > 6 ||
            !std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c); }))
            throw bad("'" + s + "' is not a whole number");
        return std::stoi(s);
    };
    Shard s{number(spec.substr(0, slash)), number(spec.substr(slash + 1))};
    if (s.count < 1) throw bad("N must be at least 1");
    if (s.index >= s.count) throw bad("i must be less than N");
    return s;
}

std::vector<WorkUnit> workUnits(const std::vector<Cell>& cells) {
    std::vector<WorkUnit> units;
    std::map<std::string, size_t> chainOfScene;  // stop-after-failure units by scene
    for (size_t i = 0; i < cells.size();) {
        size_t j = i + 1;
        while (j < cells.size() && cells[j].batchKey() == cells[i].batchKey()) ++j;
        bool chained = false;
        for (size_t k = i; k < j; ++k) chained = chained || cells[k].stopAfterFailure;
        if (!chained) {
            units.push_back({{{i, j}}});
        } else {
            auto [it, fresh] = chainOfScene.emplace(cells[i].scene, units.size());
            if (fresh) units.emplace_back();
            units[it->second].batches.push_back({i, j});
        }
        i = j;
    }
    return units;
}

std::vector<DeviceInfo> selectDevices(const std::string& spec) {
    std::vector<DeviceInfo> out;
    if (spec == "all") {
        std::vector<DeviceInfo> all = listDevices();
        for (const DeviceInfo& d : all)
            if (d.isGpu()) out.push_back(d);
        if (out.empty()) out = all;
        if (out.empty()) throw Error("--devices all: no OpenCL device found");
        return out;
    }
    size_t a = 0;
    while (a <= spec.size()) {
        size_t b = spec.find(',', a);
        if (b == std::string::npos) b = spec.size();
        std::string one = spec.substr(a, b - a);
        if (one.empty())
            throw Error("--devices " + spec +
                        ": an empty entry (expected all, or "
                        "indices and names separated by commas)");
        try {
            out.push_back(selectDevice(one));
        } catch (const Error& e) {
            // selectDevice names the flag it serves (--device); the user typed --devices.
            std::string why = e.what();
            if (why.rfind("--device ", 0) == 0) why = why.substr(9);
            throw Error("--devices " + spec + ": " + why);
        }
        a = b + 1;
    }
    return out;
}

}  // namespace rt::bench
