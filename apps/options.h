// rtlab — the render flags every front end shares (rtlab render, rtlab sweep, rtlab-view).
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <map>
#include <optional>
#include <string>

#include "core/kernel_sources.h"
#include "core/scene.h"

namespace rt::cli {

struct SceneFlags {
    std::string device;
    std::string size;  // "WxH"
    std::optional<int> bounces, shadowSamples, aa;
    std::optional<float> shadowStrength;
    bool adaptive = false;
    std::string memoryBudget;  // bytes, with optional K/M/G suffix
    // The flags of the options pipelines declare (PipelineInfo::options), by option name:
    // whole numbers and choices as given, unset or empty when not.
    std::map<std::string, std::optional<long long>> pipelineIntegers;
    std::map<std::string, std::string> pipelineChoices;
    std::string accel;
    std::string offset;  // fixed, scaled or bound; empty = the scene's default
    bool plainSphere = false, mollerTrumbore = false, fixedOffset = false;
    std::string kernelDir;
    double maxLaunchMs = 100;
    CLI::Option* maxLaunchOption = nullptr;  // given on the command line, or its default?

    void add(CLI::App& cmd);
    // The scene's defaults overridden by whatever was given; throws rt::Error naming the flag.
    RenderOptions apply(RenderOptions defaults) const;
    KernelSources kernelSources() const;
};

// Adds --pipeline to cmd: any registered name (pipelines/registry.h), or only the device
// pipelines when withReference is false; its help lists every entry with its description.
CLI::Option* addPipelineOption(CLI::App& cmd, std::string& value, bool withReference);

// Parses "640x480"; throws rt::Error("--size ...") otherwise.
void parseSize(const std::string& text, int& width, int& height);
// Parses "512", "64K", "1.5M", "2G"; throws rt::Error naming --memory-budget.
size_t parseBytes(const std::string& text, const std::string& flag);
// Throws rt::Error when the image cannot be written there (unknown extension, missing folder).
void checkOutputPath(const std::filesystem::path& path);

}  // namespace rt::cli
