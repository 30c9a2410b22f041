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

}  // namespace

std::vector<PipelineOption> megakernelOptions() { return {layoutOption()}; }

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

const char* megaLayoutName(MegaLayout layout) {
    return layoutOption().choices.at(size_t(layout)).c_str();
}

}  // namespace rt
