// rtlab sweep — converged references and frame scoring (see sweep_accuracy.h).
#include "apps/sweep_accuracy.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include "bench/pfm.h"
#include "bench/sweep_runner.h"
#include "core/error.h"
#include "core/reference.h"
#include "core/scene_loader.h"
#include "core/version.h"
#include "image/compare.h"
#include "image/image_io.h"

namespace rt::cli {
namespace fs = std::filesystem;

namespace {

uint64_t fnv1a(const std::string& s, uint64_t h = 1469598103934665603ull) {
    for (unsigned char c : s) h = (h ^ c) * 1099511628211ull;
    return h;
}

std::string fileText(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

fs::path cacheDir() {
    if (const char* d = std::getenv("RTLAB_CACHE_DIR"); d && *d) return fs::path(d) / "reference";
    if (const char* h = std::getenv("HOME"); h && *h) return fs::path(h) / ".cache/rtlab/reference";
    return fs::temp_directory_path() / "rtlab-reference";
}

// The oracle (renderOracle: core/SHADING.md section 3) for a scene at a size, from the cache when
// the scene file, the settings and the build are unchanged.
Image reference(const Scene& scene, const fs::path& file, const RenderOptions& o) {
    std::ostringstream key;
    key << fileText(file) << '|' << o.width << 'x' << o.height << '|' << o.bounces << '|'
        << o.shadowSamples << '|' << o.aa << "|oracle|" << RTLAB_COMMIT;
    char hash[17];
    std::snprintf(hash, sizeof hash, "%016llx", (unsigned long long)fnv1a(key.str()));
    fs::path cached = cacheDir() / (scene.name + "-" + std::to_string(o.width) + "x" +
                                    std::to_string(o.height) + "-" + hash + ".pfm");
    std::fprintf(stderr, "oracle %s %dx%d b%d s%d aa%d (cpu, double): ", scene.name.c_str(),
                 o.width, o.height, o.bounces, o.shadowSamples, o.aa);
    if (fs::exists(cached)) {
        std::fprintf(stderr, "cached %s\n", cached.string().c_str());
        return bench::readPfm(cached);
    }
    std::fflush(stderr);
    auto t0 = std::chrono::steady_clock::now();
    Image image = renderOracle(scene, o);
    double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::fprintf(stderr, "rendered in %s\n", bench::formatDuration(s).c_str());
    std::error_code ec;
    fs::create_directories(cached.parent_path(), ec);
    if (!ec) bench::writePfm(image, cached);
    return image;
}

}  // namespace

void scoreFrames(nlohmann::json& rows, std::vector<PendingFrame>& frames,
                 const bench::SweepConfig& config, const fs::path& sceneDir) {
    std::map<std::string, Scene> scenes;
    std::map<std::string, Image> references;
    for (PendingFrame& f : frames) {
        nlohmann::json& row = rows.at(f.row);
        std::string name = row.at("scene");
        fs::path file = bench::scenePath(name, sceneDir);
        if (!scenes.count(name)) scenes.emplace(name, loadScene(file, readImage));
        const Scene& scene = scenes.at(name);
        RenderOptions o = scene.defaults;
        o.width = row.at("width");
        o.height = row.at("height");
        o.bounces = config.referenceBounces;
        o.shadowSamples = config.referenceShadowSamples;
        o.aa = config.referenceAa;
        std::string key = name + "|" + std::to_string(o.width) + "x" + std::to_string(o.height);
        if (!references.count(key)) references.emplace(key, reference(scene, file, o));
        // Linear values clamped to [0, 1], as every accuracy figure of the project.
        ImageDiff d = compareImages(f.image, references.at(key), 1.0 / 255.0, true);
        // A frame with a NaN or infinite pixel has no accuracy score: its error figures are
        // written as null (JSON has no infinity) and the row says why.
        row["nonfinite_pixels"] = d.nonfinite;
        row["accuracy_ok"] = d.nonfinite == 0;
        if (d.nonfinite) {
            row["rmse"] = row["mean_abs"] = row["max_abs"] = row["psnr_db"] = nullptr;
        } else {
            row["rmse"] = d.rmse;
            row["mean_abs"] = d.meanAbs;
            row["max_abs"] = d.maxAbs;
            row["psnr_db"] = d.rmse > 0 ? 20.0 * std::log10(1.0 / d.rmse) : 999.0;
        }
        row["fraction_within_1_255"] = d.fractionWithin;
        // The acne rate: pixels more than 2/255 off the oracle, where the frame has the oracle's
        // settings (elsewhere the difference would count what the settings change too).
        const bool sameSettings = row.at("bounces") == o.bounces &&
                                  row.at("shadow_samples") == o.shadowSamples &&
                                  row.at("aa") == o.aa;
        if (sameSettings)
            row["acne_2_255"] =
                1.0 - compareImages(f.image, references.at(key), 2.0 / 255.0, true).fractionWithin;
        else
            row["acne_2_255"] = nullptr;
        row["reference"] = {{"pipeline", "oracle"},
                            {"bounces", o.bounces},
                            {"shadow_samples", o.shadowSamples},
                            {"aa", o.aa}};
        f.image = Image();  // free as we go
    }
}

}  // namespace rt::cli
