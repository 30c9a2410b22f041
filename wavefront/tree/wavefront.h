// rtlab — host driver of the wavefront pipeline (wavefront/tree/wavefront.cl): trace, image and
// reset kernels around a global ray tree of W x rows x N slots (node payloads, and the traced flags
// in a buffer of their own), in row tiles when it must, over a row window when asked (the viewer's
// pieces of a slow frame), reporting progress by rows x AA passes.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "core/device_pipeline.h"
#include "core/launch_planner.h"

namespace rt {

class WavefrontPipeline : public DevicePipeline {
  public:
    explicit WavefrontPipeline(ClContext& cl) : DevicePipeline(cl) {}
    const char* name() const override { return "wave"; }

    // Bytes of one pixel's tree: N node payloads and RT_TRACED_WORDS(N) words of traced flags.
    // Every tree size (rows per tile, budgets, messages, stats) is counted from it.
    // nodeBytes: a Node's size in the scene's programs (dev::nodeBytes of its light count).
    static size_t pixelBytes(int branching, int bounces, size_t nodeBytes = sizeof(dev::Node));
    // Rows per tile for a frame, given the budget for the tree (payload and
    // flag buffers together, bytes). Throws rt::Error
    // naming the bounce limit that would fit when not even one row does.
    static int tileRows(int width, int height, int branching, int bounces, size_t budget,
                        const std::string& budgetName, size_t nodeBytes = sizeof(dev::Node));
    // Row tiles a frame of `height` rows needs at `rows` rows per tile: the one place it is
    // counted.
    static int tileCount(int height, int rows) { return (height + rows - 1) / rows; }

    // For tests. poisonPayloads fills every node payload of the last frame's tree with quiet NaNs,
    // whose bytes also read as a node traced from inside an object (flags 0x7f): a kernel that
    // read a slot its pass did not reach would show it in the image. tracedFlags reads the flag
    // words back (all zero between frames).
    void poisonPayloads();
    std::vector<uint32_t> tracedFlags();

  private:
    Image renderFrame(const Scene& scene, const RenderOptions& options) override;

    DeviceBuffer tree_, traced_, image_;  // node payloads, traced flags, the image
    // What the tree buffers were sized for: rows of a frame `treeWidth_` wide at pixelBytes().
    int treeRows_ = 0, treeWidth_ = 0;
    size_t treePixelBytes_ = 0;
    bool needsClear_ = false;  // a new flag buffer not yet cleared
    LaunchPlanner planner_;
};

}  // namespace rt
