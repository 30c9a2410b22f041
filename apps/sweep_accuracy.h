// rtlab sweep — the accuracy side of a sweep: the converged reference (CPU, double precision, a
// high bounce limit and sample counts; cached on disk) and the comparison of kept frames with it
// through OpenImageIO (image/compare.h).
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench/sweep_config.h"
#include "core/image.h"

namespace rt::cli {

struct PendingFrame {
    size_t row;  // index into the rows being scored
    Image image;
};

// Adds "rmse", "mean_abs", "max_abs", "psnr_db" and "reference" to each pending frame's row.
// Scenes are loaded from sceneDir (empty: scenes/ of the checkout) with OpenImageIO.
void scoreFrames(nlohmann::json& rows, std::vector<PendingFrame>& frames,
                 const bench::SweepConfig& config, const std::filesystem::path& sceneDir);

}  // namespace rt::cli
