// rtlab compare: the testbed's main job in one command. Renders a scene with the independent
// oracle (core/reference.h renderOracle), the CPU reference (the renderers' method in double) and
// every registered pipeline on one device, and prints each pipeline's device time (median of
// repeats after a warm-up frame) beside its error against the oracle and its acne rate (pixels
// more than 2/255 off the oracle), then how far each pair of pipelines differs (by design, not
// at all).
#include "image/compare.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "apps/commands.h"
#include "apps/options.h"
#include "core/cl_runtime.h"
#include "core/error.h"
#include "core/pipeline.h"
#include "core/scene_loader.h"
#include "core/version.h"
#include "image/image_io.h"
#include "pipelines/registry.h"

namespace rt::cli {

namespace {

struct CompareArgs {
    std::string scene;
    std::string outputPrefix;
    SceneFlags flags;
    int repeats = 5;
} compareArgs;

CLI::App* compareCmd = nullptr;

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0 : v[v.size() / 2];
}

}  // namespace

void addCompare(CLI::App& app) {
    CompareArgs& a = compareArgs;
    compareCmd = app.add_subcommand(
        "compare",
        "Render one scene with the independent oracle, the CPU reference "
        "and every pipeline (" +
            pipelineRegistry().joinedNames(true) + "); print time and error side by side");
    compareCmd
        ->add_option("scene", a.scene,
                     "Scene file (.json or .nff) or model (.obj, .gltf, .glb, .ply)")
        ->required();
    compareCmd->add_option("-o,--output-prefix", a.outputPrefix,
                           "Also write PREFIX-<pipeline>.png for each pipeline and the reference");
    compareCmd->add_option("--repeats", a.repeats, "Timed frames per pipeline (median is shown)")
        ->check(CLI::Range(1, 1000))
        ->capture_default_str();
    a.flags.add(*compareCmd);
}

bool compareParsed() { return compareCmd && compareCmd->parsed(); }

int runCompare() {
    CompareArgs& a = compareArgs;
    // A bad -o fails before minutes of rendering, not after.
    if (!a.outputPrefix.empty()) {
        std::filesystem::path dir = std::filesystem::path(a.outputPrefix).parent_path();
        if (!dir.empty() && !std::filesystem::is_directory(dir))
            throw Error("--output-prefix " + a.outputPrefix + ": folder " + dir.string() +
                        " does not exist");
    }
    Scene scene = loadScene(a.scene, readImage);
    for (const std::string& note : scene.notes)
        std::fprintf(stderr, "rtlab: note: %s\n", note.c_str());
    RenderOptions o = a.flags.apply(scene.defaults);
    ClContext cl(selectDevice(a.flags.device), a.flags.kernelSources());
    std::printf("rtlab compare: %s, %dx%d, bounces %d, shadow samples %d, aa %d, C=%d\n",
                scene.name.c_str(), o.width, o.height, o.bounces, o.shadowSamples, o.aa,
                scene.branching());
    std::printf("device %s, commit %s\n\n", cl.device().label().c_str(), RTLAB_COMMIT);

    const PipelineRegistry& registry = pipelineRegistry();
    auto oracle = makePipeline("oracle", nullptr);
    Image reference = oracle->render(scene, o);
    const double oracleMs = oracle->stats().hostMs;
    if (!a.outputPrefix.empty()) writeImage(reference, a.outputPrefix + "-oracle.png");
    auto cpu = makePipeline("cpu", nullptr);
    const Image method = cpu->render(scene, o);
    const double cpuMs = cpu->stats().hostMs;
    if (!a.outputPrefix.empty()) writeImage(method, a.outputPrefix + "-cpu.png");
    const ImageDiff cpuDiff = compareImages(method, reference, 2.0 / 255.0);

    const std::vector<std::string> names = registry.names(true);
    int w = 6;  // the first column: as wide as the longest pipeline name
    for (const std::string& n : registry.names()) w = std::max(w, int(n.size()));
    std::printf("errors against the oracle; acne = pixels more than 2/255 off it\n");
    std::printf("%-*s %12s %12s %10s %12s %12s %12s %10s %9s\n", w, "pipe", "device ms", "host ms",
                "acne", "mean |err|", "max |err|", "rays", "Mrays/s", "launches");
    std::printf("%-*s %12s %12.2f %10s %12s %12s %12s %10s %9s\n", w, "oracle", "-", oracleMs,
                "oracle", "-", "-", "-", "-", "-");
    std::printf("%-*s %12s %12.2f %9.3f%% %8.3f/255 %8.2f/255 %12s %10s %9s\n", w, "cpu", "-",
                cpuMs, 100.0 * (1.0 - cpuDiff.fractionWithin), cpuDiff.meanAbs * 255.0,
                cpuDiff.maxAbs * 255.0, "-", "-", "-");
    std::vector<Image> images;
    long long nonfinite = countNonFinite(reference);
    std::vector<std::string> compared, notes;
    for (const std::string& name : names) {
        // Adaptive anti-aliasing is compared only where a pipeline has it (the registry says).
        if (o.adaptiveAa && !registry.get(name).supports.adaptiveAa) {
            std::printf("%-*s %12s   (no adaptive anti-aliasing: not compared)\n", w, name.c_str(),
                        "-");
            continue;
        }
        auto p = makePipeline(name, &cl);
        Image img = p->render(scene, o);  // warm-up: builds the program, allocates buffers
        std::vector<double> dev, host;
        for (int r = 0; r < a.repeats; ++r) {
            img = p->render(scene, o);
            dev.push_back(p->stats().deviceMs);
            host.push_back(p->stats().hostMs);
        }
        const int launches = p->stats().launches;
        // Rays counted in one more frame, untimed: the device counters cost time of their own.
        RenderOptions counted = o;
        counted.countRays = true;
        p->render(scene, counted);
        unsigned long long rays = 0;
        if (p->stats().raysCounted)
            for (int t = 0; t < RT_RAY_TYPES; ++t) rays += p->stats().rays[t];
        ImageDiff d = compareImages(img, reference, 2.0 / 255.0);
        nonfinite += countNonFinite(img);
        std::printf("%-*s %12.3f %12.3f %9.3f%% %8.3f/255 %8.2f/255 %12llu %10.1f %9d\n", w,
                    name.c_str(), median(dev), median(host), 100.0 * (1.0 - d.fractionWithin),
                    d.meanAbs * 255.0, d.maxAbs * 255.0, rays,
                    median(dev) > 0 ? double(rays) / (median(dev) * 1e3) : 0.0, launches);
        if (!a.outputPrefix.empty()) writeImage(img, a.outputPrefix + "-" + name + ".png");
        images.push_back(std::move(img));
        compared.push_back(name);
        if (!p->stats().note.empty()) notes.push_back(p->stats().note);
    }
    std::printf("\n");
    for (const std::string& note : notes) std::printf("%s\n", note.c_str());
    if (!notes.empty()) std::printf("\n");
    for (size_t i = 0; i < compared.size(); ++i)
        for (size_t j = i + 1; j < compared.size(); ++j) {
            ImageDiff d = compareImages(images[i], images[j], 0.0, false);
            std::printf("%s vs %s: max |difference| %.3g (%s)\n", compared[i].c_str(),
                        compared[j].c_str(), d.maxAbs,
                        d.maxAbs == 0 ? "bit-identical" : "not bit-identical");
        }
    // A NaN or infinite pixel is a broken frame whatever the error figures say.
    if (nonfinite)
        throw Error(std::to_string(nonfinite) +
                    " non-finite (NaN or infinite) pixel(s) in the frames above");
    return 0;
}

}  // namespace rt::cli
