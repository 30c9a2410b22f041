// rtlab bench — how a sweep's cells are handed out: to the devices of one host (--devices, one
// worker thread and one OpenCL context each, taking work units from a shared queue) and to the
// machines of a cluster (--shard i/N, a fixed share of the work units per machine). Both split
// the same units, so a sweep gives the same rows, in the same order, however it is spread.
#pragma once

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "bench/sweep_config.h"
#include "core/cl_runtime.h"

namespace rt::bench {

// One share of a sweep: the work units whose index % count == index. Round robin rather than
// contiguous blocks, because a sweep file lists its costly groups together (full: 4K last).
struct Shard {
    int index = 0, count = 1;
    bool whole() const { return count == 1; }
    std::string str() const { return std::to_string(index) + "/" + std::to_string(count); }
};
// "i/N" with 0 <= i < N; throws rt::Error "--shard SPEC: ..." otherwise.
Shard parseShard(const std::string& spec);

// What one worker runs without looking at the others' results: the batches (runs of adjacent
// cells whose frames are interleaved, Cell::batchKey) in cell order. Every batch is a unit of
// its own, except those of stop-after-failure groups: a failure there skips later, larger
// cells of the same scene, so a scene's such batches form one unit, run in order.
struct WorkUnit {
    std::vector<std::pair<size_t, size_t>> batches;  // cell index ranges [begin, end)
};
std::vector<WorkUnit> workUnits(const std::vector<Cell>& cells);

// --devices: "all" (every GPU; every device when there is none), or a comma-separated list of
// indices and name substrings as --device takes them; a device may be named twice (two contexts
// on one device). Throws rt::Error "--devices SPEC: ..." naming what matched nothing.
std::vector<DeviceInfo> selectDevices(const std::string& spec);

}  // namespace rt::bench
