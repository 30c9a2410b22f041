// rtlab — the megakernel's option declaration and its typed read-back (megakernel_options.h).
#include "megakernel/megakernel_options.h"

namespace rt {

namespace {

const PipelineOption& layoutOption() {
    static const PipelineOption o{
        .name = "layout",
        .type = PipelineOption::Type::Choice,
        .help =
            "Megakernel ray storage: tree (report, N nodes) or weighted (B*(C-1)+1 rays) "
            "[tree]",
        .defaultValue = "tree",
        .choices = {"tree", "weighted"},  // MegaLayout's order
        .sweepKey = "layout",
        .cellTag = "W",
        // The value alone: a cell label reads "... weighted".
        .label = "{}",
    };
    return o;
}

// A cap on the registers a work-item, for NVIDIA's compiler: fewer registers let more warps share
// a multiprocessor, at the cost of spills to local memory.
const PipelineOption& registersOption() {
    static const PipelineOption o{
        .name = "max-registers",
        .type = PipelineOption::Type::Integer,
        .help =
            "Megakernel on NVIDIA: at most this many registers a work-item, 16..255 "
            "(-cl-nv-maxrregcount); more warps fit a multiprocessor, at the cost of spills. "
            "Other devices ignore it [0: the compiler's choice]",
        .defaultValue = 0ll,
        .min = 16,
        .max = 255,
        .sweepKey = "max-registers",
        .cellTag = "Y",
        .label = "at most {} registers",
    };
    return o;
}

}  // namespace

std::vector<PipelineOption> megakernelOptions() { return {layoutOption(), registersOption()}; }

std::vector<PipelineVariant> megakernelVariants() {
    std::vector<PipelineVariant> out;
    for (MegaLayout l : {MegaLayout::Tree, MegaLayout::Weighted}) {
        PipelineVariant v{megaLayoutName(l), {}};
        layoutOption().set(v.values, v.name);
        out.push_back(std::move(v));
    }
    return out;
}

MegaLayout megaLayout(const RenderOptions& o) {
    return MegaLayout(layoutOption().index(o.pipelineOptions));
}

void setMegaLayout(RenderOptions& o, MegaLayout layout) {
    layoutOption().set(o.pipelineOptions, megaLayoutName(layout));
}

int megaMaxRegisters(const RenderOptions& o) {
    return int(registersOption().integer(o.pipelineOptions));
}

void setMegaMaxRegisters(RenderOptions& o, int registers) {
    registersOption().set(o.pipelineOptions, (long long)registers);
}

const char* megaLayoutName(MegaLayout layout) {
    return layoutOption().choices.at(size_t(layout)).c_str();
}

}  // namespace rt
