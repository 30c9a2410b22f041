#include "apps/options.h"

#include <cmath>
#include <cstdlib>
#include <regex>

#include "core/accel.h"
#include "core/error.h"
#include "core/pipeline.h"
#include "pipelines/registry.h"

namespace rt::cli {

void SceneFlags::add(CLI::App& cmd) {
    cmd.add_option("--device", device,
                   "OpenCL device: index or name substring from `rtlab devices` "
                   "[$RTLAB_DEVICE, else first GPU, else CPU]");
    cmd.add_option("--size", size, "Image size WxH [scene default]");
    cmd.add_option(
        "--bounces", bounces,
        "Bounce limit B, 0.." + std::to_string(RT_MAX_BOUNCE_LIMIT) + " [scene default]");
    cmd.add_option("--shadow-samples", shadowSamples,
                   "Shadow rays per light of non-zero radius, 1..255 [scene default]");
    cmd.add_option("--aa", aa, "Anti-aliasing: N x N samples per pixel, 1..16 [scene default]");
    cmd.add_flag("--adaptive", adaptive,
                 "Supersample only edge pixels (report 2.1.2); megakernel and cpu only: the "
                 "wavefront refuses it");
    cmd.add_option("--shadow-strength", shadowStrength,
                   "How much a fully occluded light darkens, 0..1 [scene default]");
    cmd.add_option("--memory-budget", memoryBudget,
                   "Wavefront: bytes the global ray tree may use (e.g. 64M); frames past it are "
                   "rendered in row tiles [device max allocation]");
    // Each pipeline's own options, in registration order; checked when applied, by their
    // declarations, so that every front end says a bad value the same way.
    for (const PipelineOption* opt : pipelineRegistry().options()) {
        if (opt->type == PipelineOption::Type::Integer)
            cmd.add_option(opt->flag(), pipelineIntegers[opt->name], opt->help);
        else
            cmd.add_option(opt->flag(), pipelineChoices[opt->name], opt->help);
    }
    cmd.add_option("--accel", accel,
                   "How rays find spheres and triangles: none (per-mesh bounding sphere only), "
                   "bv (plus 7 slab pairs per mesh), grid (uniform grid), bvh (SAH BVH), wide "
                   "(the SAH BVH as 4-wide nodes with quantised boxes) or cwbvh (as compressed "
                   "8-wide nodes in ray-octant order, for GPUs) "
                   "[scene's render.accel, else bvh above 64 spheres and triangles, else bv with "
                   "triangles, else none]");
    cmd.add_flag("--plain-sphere", plainSphere,
                 "Use the report's quadratic sphere test instead of the robust one");
    cmd.add_flag("--moller-trumbore", mollerTrumbore,
                 "Use Moller-Trumbore (report Algorithm 3) instead of the watertight test");
    cmd.add_option("--offset", offset,
                   "Where secondary rays start (core/SHADING.md section 3): bound (past a bound on "
                   "the hit point's rounding error, scale-free), scaled (1e-4 max(1, |p|)) or "
                   "fixed (1e-4) [bound]");
    cmd.add_flag("--fixed-offset", fixedOffset, "Same as --offset fixed");
    maxLaunchOption =
        cmd.add_option(
               "--max-launch-ms", maxLaunchMs,
               "Split frames into row tiles (and a costly row into column pieces; the queue "
               "wavefront admits fewer rays and runs a long stage in pieces) so that no kernel "
               "launch runs longer than this (display-driver watchdogs); 0 = one launch per "
               "frame")
            ->check(CLI::Range(0.0, 1e6))
            ->capture_default_str();
    cmd.add_option("--kernel-dir", kernelDir,
                   "Read kernel sources from this source tree instead of the embedded copies "
                   "[$RTLAB_KERNEL_DIR]");
}

CLI::Option* addPipelineOption(CLI::App& cmd, std::string& value, bool withReference) {
    const PipelineRegistry& registry = pipelineRegistry();
    std::string help = "Pipeline, one of " + registry.joinedNames(!withReference) + ":";
    for (const PipelineInfo& p : registry.all())
        if (withReference || !p.reference)
            help += "\n  " + p.name + ": " + p.title + ", " + p.description;
    return cmd.add_option("--pipeline", value, help)
        ->check(CLI::IsMember(registry.names(!withReference)))
        ->capture_default_str();
}

void parseSize(const std::string& text, int& width, int& height) {
    static const std::regex re("([0-9]{1,6})[xX]([0-9]{1,6})");
    std::smatch m;
    if (!std::regex_match(text, m, re))
        throw Error("--size " + text + ": expected WIDTHxHEIGHT, e.g. 640x480");
    width = std::stoi(m[1]);
    height = std::stoi(m[2]);
    if (width < 1 || height < 1 || width > 16384 || height > 16384)
        throw Error("--size " + text + ": width and height must be in 1..16384");
}

size_t parseBytes(const std::string& text, const std::string& flag) {
    static const std::regex re("([0-9]+(\\.[0-9]+)?)([kKmMgG]?)[bB]?");
    std::smatch m;
    if (!std::regex_match(text, m, re))
        throw Error(flag + " " + text + ": expected a byte count such as 4096, 64K, 512M or 2G");
    double v = std::stod(m[1]);
    char unit = m[3].length() ? char(std::toupper(m[3].str()[0])) : ' ';
    double scale = unit == 'K'   ? 1024.0
                   : unit == 'M' ? 1048576.0
                   : unit == 'G' ? 1073741824.0
                                 : 1.0;
    double bytes = v * scale;
    if (!(bytes >= 1) || bytes > 1e15) throw Error(flag + " " + text + ": out of range");
    return size_t(std::llround(bytes));
}

RenderOptions SceneFlags::apply(RenderOptions o) const {
    if (!size.empty()) parseSize(size, o.width, o.height);
    if (bounces) o.bounces = *bounces;
    if (shadowSamples) o.shadowSamples = *shadowSamples;
    if (aa) o.aa = *aa;
    if (shadowStrength) o.shadowStrength = *shadowStrength;
    if (adaptive) o.adaptiveAa = true;
    if (!memoryBudget.empty()) o.memoryBudget = parseBytes(memoryBudget, "--memory-budget");
    const PipelineRegistry& registry = pipelineRegistry();
    for (const PipelineOption* opt : registry.options()) {
        if (auto it = pipelineIntegers.find(opt->name); it != pipelineIntegers.end() && it->second)
            opt->set(o.pipelineOptions, *it->second);
        if (auto it = pipelineChoices.find(opt->name);
            it != pipelineChoices.end() && !it->second.empty())
            opt->set(o.pipelineOptions, it->second);
    }
    if (!accel.empty()) o.accel = parseAccel(accel);
    if (plainSphere) o.robustSphere = false;
    if (mollerTrumbore) o.watertight = false;
    if (!offset.empty()) o.offset = parseOffset(offset);
    if (fixedOffset) {
        if (!offset.empty() && o.offset != RenderOptions::Offset::Fixed)
            throw Error("--fixed-offset contradicts --offset " + offset);
        o.offset = RenderOptions::Offset::Fixed;
    }
    o.maxLaunchMs = maxLaunchMs;
    // A pipeline's own options may not go with the default launch cap (PipelineInfo::
    // settleDefaults); a cap asked for stays, for the pipeline to accept or refuse.
    const bool capGiven = maxLaunchOption && maxLaunchOption->count() > 0;
    for (const PipelineInfo& p : registry.all())
        if (p.settleDefaults) p.settleDefaults(o, capGiven);
    auto range = [](const char* flag, int v, int lo, int hi) {
        if (v < lo || v > hi)
            throw Error(std::string(flag) + " " + std::to_string(v) + ": must be in " +
                        std::to_string(lo) + ".." + std::to_string(hi));
    };
    range("--bounces", o.bounces, 0, RT_MAX_BOUNCE_LIMIT);
    range("--shadow-samples", o.shadowSamples, 1, 255);
    range("--aa", o.aa, 1, 16);
    if (!(o.shadowStrength >= 0.f && o.shadowStrength <= 1.f))
        throw Error("--shadow-strength " + std::to_string(o.shadowStrength) + ": must be in 0..1");
    return o;
}

KernelSources SceneFlags::kernelSources() const {
    std::string dir = kernelDir;
    if (dir.empty())
        if (const char* env = std::getenv("RTLAB_KERNEL_DIR"); env && *env) dir = env;
    return KernelSources(dir);
}

void checkOutputPath(const std::filesystem::path& path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec))
        throw Error("--output " + path.string() + ": is a folder; give a file name such as " +
                    (path / "render.png").string());
    std::string ext = path.extension().string();
    for (char& c : ext) c = char(std::tolower((unsigned char)c));
    if (ext != ".png" && ext != ".exr" && ext != ".jpg" && ext != ".jpeg" && ext != ".tif" &&
        ext != ".tiff" && ext != ".hdr")
        throw Error("--output " + path.string() +
                    ": unsupported image type (use .png, .exr, .jpg, .tif or .hdr)");
    std::filesystem::path dir = path.parent_path();
    if (!dir.empty() && !std::filesystem::is_directory(dir))
        throw Error("--output " + path.string() + ": folder " + dir.string() + " does not exist");
}

}  // namespace rt::cli
