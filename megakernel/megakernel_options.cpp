// rtlab — the megakernel's option declaration and its typed read-back (megakernel_options.h).
#include "megakernel/megakernel_options.h"

#include "core/cl_runtime.h"

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

const PipelineOption& registersOption() {
    static const PipelineOption o = registerCapOption("max-registers", "Megakernel", "", "Y");
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

PipelineOption registerCapOption(const std::string& name, const std::string& who,
                                 const std::string& hint, const std::string& cellTag) {
    return PipelineOption{
        .name = name,
        .type = PipelineOption::Type::Integer,
        .help = who +
                " on NVIDIA: at most this many registers a work-item, 16..255 "
                "(-cl-nv-maxrregcount); more warps fit a multiprocessor, at the cost of spills" +
                hint + ". Other devices ignore it [0: the compiler's choice]",
        .defaultValue = 0ll,
        .min = 16,
        .max = 255,
        .sweepKey = name,
        .cellTag = cellTag,
        .label = "at most {} registers",
    };
}

std::vector<std::string> registerCapBuildOptions(long long registers, const DeviceInfo& device) {
    if (registers == 0 || !device.nvidia()) return {};
    return {"-cl-nv-maxrregcount=" + std::to_string(registers)};
}

}  // namespace rt
