// The pipeline registry: front ends see pipelines only through it, so it must list the
// CPU reference first and every pipeline folder once, refuse a second entry under one name, and
// name every choice when asked for one it lacks.
#include "pipelines/registry.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>

#include "bench/sweep_config.h"
#include "core/accel.h"
#include "core/error.h"
#include "core/pipeline_options.h"
#include "core/scene_loader.h"
#include "image/compare.h"
#include "image/image_io.h"
#include "megakernel/megakernel_options.h"
#include "test_device.h"
#include "test_images.h"
#include "test_sweep.h"
#include "wavefront/queue/queue_options.h"

namespace rt {
namespace {

TEST(Registry, ListsTheReferenceAndTheOracleFirstAndEveryPipelineOnce) {
    const PipelineRegistry& r = pipelineRegistry();
    ASSERT_GE(r.all().size(), 3u);
    EXPECT_TRUE(r.all()[0].reference);
    std::set<std::string> seen;
    for (const PipelineInfo& p : r.all()) {
        EXPECT_TRUE(seen.insert(p.name).second) << p.name;
        EXPECT_FALSE(p.title.empty()) << p.name;
        EXPECT_FALSE(p.description.empty()) << p.name;
        EXPECT_EQ(p.reference, &p == &r.all()[0] || &p == &r.all()[1])
            << "the CPU reference and the oracle, listed first: " << p.name;
    }
    // The two the project began with stay registered under their sweep-row names.
    EXPECT_NE(r.find("mega"), nullptr);
    EXPECT_NE(r.find("wave"), nullptr);
    EXPECT_EQ(r.all()[1].name, "oracle");
    EXPECT_EQ(r.names(true).size(), r.all().size() - 2);
}

TEST(Registry, EveryPipelineMakesOneThatKnowsItsName) {
    for (const PipelineInfo& p : pipelineRegistry().all()) {
        std::unique_ptr<Pipeline> made = makePipeline(p.name, &test::device());
        EXPECT_EQ(std::string(made->name()), p.name);
    }
}

TEST(Registry, UnknownNameListsEveryChoice) {
    try {
        pipelineInfo("gpu");
        FAIL() << "an unknown pipeline was found";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), FailureKind::InvalidOption);
        std::string msg = e.what();
        EXPECT_NE(msg.find("--pipeline gpu"), std::string::npos) << msg;
        for (const std::string& n : pipelineRegistry().names())
            EXPECT_NE(msg.find(n), std::string::npos) << msg;
    }
}

TEST(Registry, RefusesADuplicateName) {
    PipelineRegistry r;
    r.add(referencePipelineInfo());
    EXPECT_THROW(r.add(referencePipelineInfo()), Error);
    EXPECT_THROW(r.make("mega", nullptr), Error);  // not in this registry
}

// Sweep rows record each pipeline's design family, which the crossover map compares: a pipeline
// must say which it is.
TEST(Registry, RefusesAPipelineWithoutAFamily) {
    PipelineRegistry r;
    PipelineInfo p = referencePipelineInfo();
    p.family.clear();
    EXPECT_THROW(r.add(p), Error);
    for (const PipelineInfo& info : pipelineRegistry().all())
        EXPECT_FALSE(info.family.empty()) << info.name;
    EXPECT_EQ(pipelineInfo("mega").family, "megakernel");
    EXPECT_EQ(pipelineInfo("queue").family, "wavefront");
}

// What lets a new pipeline in without a test of its own: every device pipeline renders the same
// image as the first one registered (they share the stage code in core/cl): within 1e-5 per
// channel, the bar for a pipeline that adds a path's contributions in another order
// (the queue sums bounce by bounce, the megakernel depth first; float addition is not
// associative, so glass scenes differ in the last bit).
TEST(Registry, EveryDevicePipelineRendersTheSameImage) {
    Scene scene = loadScene("scenes/spheres.json", readImage);
    RenderOptions o = scene.defaults;
    o.width = 48;
    o.height = 32;
    o.bounces = 3;
    const std::vector<std::string> names = pipelineRegistry().names(true);
    Image first = makePipeline(names.at(0), &test::device())->render(scene, o);
    for (size_t i = 1; i < names.size(); ++i) {
        Image other = makePipeline(names[i], &test::device())->render(scene, o);
        ASSERT_EQ(other.rgb.size(), first.rgb.size()) << names[i];
        const ImageDiff d = compareImages(other, first, 1e-5, false);
        EXPECT_TRUE(d.allWithin()) << names[i] << " differs from " << names[0] << " by up to "
                                   << d.maxAbs << " (" << d.nonfinite << " non-finite pixels)";
    }
}

// A pipeline keeps the device copy of the last scene it rendered. A scene loaded into the same
// storage as the one before (a variable assigned, a loop's local) must not be taken for it, as
// it was when the copy was matched by address: every pipeline, auto's cached decision included,
// renders the second scene as a fresh pipeline does.
TEST(Registry, ASceneLoadedWhereAnotherLayIsNotTakenForIt) {
    Scene scene = loadScene("scenes/spheres.json", readImage);
    RenderOptions o = scene.defaults;
    o.width = 24;
    o.height = 16;
    o.bounces = 2;
    for (const std::string& name : pipelineRegistry().names(true)) {
        std::unique_ptr<Pipeline> reused = makePipeline(name, &test::device());
        reused->render(scene, o);
        scene = loadScene("scenes/envmap.json", readImage);  // same object, new contents
        const Image second = reused->render(scene, o);
        const Image fresh = makePipeline(name, &test::device())->render(scene, o);
        EXPECT_TRUE(test::sameBits(second, fresh)) << name;
        scene = loadScene("scenes/spheres.json", readImage);
    }
}

// Sweep files take any registered name, and every device pipeline when a group names none.
TEST(Registry, SweepFilesTakeTheirPipelinesFromTheRegistry) {
    bench::SweepConfig c = bench::parseSweep(
        "[a]\nscenes = spheres\n[b]\nscenes = spheres\n"
        "pipelines = wave\n",
        "test");
    EXPECT_EQ(c.groups[0].pipelines, pipelineRegistry().names(true));
    EXPECT_EQ(c.groups[1].pipelines, std::vector<std::string>{"wave"});
    for (const char* bad : {"nope", "cpu"}) {
        try {
            bench::parseSweep(std::string("[a]\nscenes = spheres\npipelines = ") + bad + "\n", "f");
            FAIL() << bad << " was accepted";
        } catch (const Error& e) {
            EXPECT_EQ(e.kind(), FailureKind::InvalidOption) << e.what();
            EXPECT_NE(std::string(e.what()).find("f:3: "), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
        }
    }
}

// A pipeline's own options come from its entry: two pipelines may not claim one option name,
// sweep key or cell tag, since flags, sweep files and cell keys are one namespace.
TEST(Registry, RefusesAnOptionTwoPipelinesDeclare) {
    auto withOption = [](const std::string& pipeline, PipelineOption o) {
        PipelineInfo p = referencePipelineInfo();
        p.name = pipeline;
        p.options = {std::move(o)};
        return p;
    };
    const PipelineOption mine{.name = "gain",
                              .type = PipelineOption::Type::Integer,
                              .help = "h",
                              .defaultValue = 1ll,
                              .min = 1,
                              .max = 4,
                              .sweepKey = "gain",
                              .cellTag = "G",
                              .label = "gain {}"};
    PipelineRegistry r;
    r.add(withOption("a", mine));
    for (auto change : {+[](PipelineOption& o) {
                            o.sweepKey = "other";
                            o.cellTag = "X";
                        },
                        +[](PipelineOption& o) {
                            o.name = "other";
                            o.cellTag = "X";
                        },
                        +[](PipelineOption& o) {
                            o.name = "other";
                            o.sweepKey = "other";
                        }}) {
        PipelineOption clash = mine;
        change(clash);
        EXPECT_THROW(r.add(withOption("b", clash)), Error) << clash.name;
    }
    PipelineOption unlabelled = mine;
    unlabelled.name = unlabelled.sweepKey = "other";
    unlabelled.cellTag = "X";
    unlabelled.label = "gain";
    EXPECT_THROW(r.add(withOption("c", unlabelled)), Error);
    ASSERT_EQ(r.options().size(), 1u);
    EXPECT_EQ(r.findSweepOption("gain"), r.options()[0]);
}

// Values are read back typed, with the declared default when unset, and checked when set, the
// error naming the flag.
TEST(Registry, OptionValuesReadBackTypedAndAreChecked) {
    const PipelineOption count{.name = "count",
                               .type = PipelineOption::Type::Integer,
                               .help = "h",
                               .defaultValue = 0ll,
                               .min = 1,
                               .max = 9,
                               .sweepKey = "count",
                               .cellTag = "C",
                               .label = "count {}"};
    const PipelineOption mode{.name = "mode",
                              .type = PipelineOption::Type::Choice,
                              .help = "h",
                              .defaultValue = "slow",
                              .choices = {"slow", "fast", "odd"},
                              .sweepKey = "mode",
                              .cellTag = "M",
                              .label = "{}"};
    PipelineOptionValues v;
    EXPECT_EQ(count.integer(v), 0);
    EXPECT_EQ(mode.index(v), 0u);
    EXPECT_TRUE(mode.isDefault(v));
    count.set(v, 7ll);
    mode.set(v, "odd");
    EXPECT_EQ(count.integer(v), 7);
    EXPECT_EQ(mode.choice(v), "odd");
    EXPECT_EQ(mode.index(v), 2u);
    EXPECT_FALSE(mode.isDefault(v));
    try {
        count.set(v, 10ll);
        FAIL();
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(), "--count 10: must be in 1..9");
    }
    try {
        mode.set(v, "quick");
        FAIL();
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(), "--mode quick: must be slow, fast or odd");
    }
    EXPECT_EQ(count.integer(v), 7) << "a refused value leaves the old one";
}

// Sweep files take every declared option under its sweep key, and cells carry it into their
// keys and labels by its declaration; a number's "default" is the declared default.
TEST(Registry, SweepFilesTakeEveryDeclaredOption) {
    for (const PipelineOption* opt : pipelineRegistry().options()) {
        const bool number = opt->type == PipelineOption::Type::Integer;
        std::string value = number ? std::to_string(opt->max) : opt->choices.back();
        std::string fallback = number ? "default" : opt->text(opt->defaultValue);
        bench::SweepConfig c =
            bench::parseSweep("[a]\nscenes = spheres\npipelines = wave\n" + opt->sweepKey + " = " +
                                  value + "\n[b]\n" + "scenes = spheres\npipelines = wave\n" +
                                  opt->sweepKey + " = " + fallback + "\n",
                              "t");
        EXPECT_EQ(opt->text(opt->value(c.groups[0].pipelineOptions)), value) << opt->name;
        EXPECT_TRUE(opt->isDefault(c.groups[1].pipelineOptions)) << opt->name;
        Scene scene = loadScene("scenes/spheres.json", readImage);
        std::vector<bench::Cell> cells =
            bench::expandCells(c, [&](const std::string&) -> const Scene& { return scene; });
        ASSERT_EQ(cells.size(), 2u) << opt->name << ": the value makes a cell of its own";
        std::string label = opt->label;
        label.replace(label.find("{}"), 2, value);
        EXPECT_NE(cells[0].key().find("|" + opt->cellTag + value), std::string::npos)
            << cells[0].key();
        EXPECT_NE(cells[0].label().find(label), std::string::npos) << cells[0].label();
        EXPECT_EQ(opt->describe(c.groups[0].pipelineOptions), label);
        EXPECT_EQ(cells[1].key().find("|" + opt->cellTag), std::string::npos) << cells[1].key();
    }
}

// A sweep's rows name the options a cell set away from their defaults in the registry's words
// ("option_labels"), by which the charts name a variant; a cell at the defaults names none.
TEST(Registry, RowsNameTheOptionsACellSet) {
    const std::vector<nlohmann::json> rows = test::sweepRows(
        "repeats = 1\nwarmup = 0\n[a]\nscenes = spheres\npipelines = persist\nsizes = 8x6\n"
        "bounces = 1\n[b]\nscenes = spheres\npipelines = persist\nsizes = 8x6\nbounces = 1\n"
        "persistent-schedule = nested\npersistent-groups = 2\n",
        "labels-test");
    ASSERT_EQ(rows.size(), 2u);
    EXPECT_EQ(rows[0]["option_labels"], nlohmann::json::object());
    const nlohmann::json set = {{"persistent-groups", "2 groups per unit"},
                                {"persistent-schedule", "nested schedule"}};
    EXPECT_EQ(rows[1]["option_labels"], set);
}

// Rows already in results/ were written when the queue's options and the megakernel's layout were
// fields of RenderOptions: the cells the same sweep file expands to now must have the keys those
// rows recorded, read through currentCellKey (resumed sweeps and merged results match rows by
// them).
// Every committed sweep file parses: its keys, pipelines and option values are what the registry
// declares (a list where an option takes one value is an error that only a device run would
// otherwise find).
TEST(Registry, EveryCommittedSweepFileParses) {
    int files = 0;
    for (const auto& e : std::filesystem::directory_iterator("bench/sweeps")) {
        if (e.path().has_extension()) continue;  // README.md
        ++files;
        try {
            const bench::SweepConfig c = bench::loadSweep(e.path());
            EXPECT_FALSE(c.groups.empty()) << e.path();
        } catch (const std::exception& x) {
            ADD_FAILURE() << x.what();
        }
    }
    EXPECT_GT(files, 20);
}

TEST(Registry, RecordedRowsKeepTheirCellKeys) {
    // The queue's options; both megakernel layouts, with and without a launch cap.
    for (const char* file : {"results/pocl-pthread-skylake-avx512-amd-epyc/queue-launch-cpu.json",
                             "results/pocl-pthread-skylake-avx512-amd-epyc/limits.json",
                             "results/nvidia-h200/queue.json"}) {
        SCOPED_TRACE(file);
        std::ifstream in(file);
        ASSERT_TRUE(in) << file;
        const nlohmann::json results = nlohmann::json::parse(in);
        std::set<std::string> recorded, pipelines;
        for (const nlohmann::json& row : results.at("rows")) {
            recorded.insert(bench::currentCellKey(row.at("cell")));
            pipelines.insert(row.at("pipeline"));
        }
        bench::SweepConfig c =
            bench::parseSweep(results.at("meta").at("config").get<std::string>(), file);
        std::map<std::string, Scene> scenes;
        std::set<std::string> now;
        for (const bench::Cell& cell :
             bench::expandCells(c, [&](const std::string& name) -> const Scene& {
                 return scenes.try_emplace(name, loadScene("scenes/" + name + ".json", readImage))
                     .first->second;
             }))
            // A file that lists no pipelines means every one registered: the ones added since
            // have cells of their own, which no row recorded.
            if (pipelines.count(cell.pipeline)) now.insert(cell.key());
        EXPECT_EQ(now, recorded);
    }
}

// Tests and the smoke check run every pipeline in each of its variants: the megakernel in both
// layouts, the persistent megakernel in each of its schedules and in the one auto chooses, the
// queue at its defaults and in small padded groups, the others once at their defaults.
TEST(Registry, VariantsCoverTheMegakernelsLayoutsAndSchedules) {
    std::vector<std::string> names;
    for (const PipelineVariantRun& v : pipelineRegistry().variants(true)) {
        names.push_back(v.name);
        RenderOptions o;
        v.apply(o);
        if (v.pipeline == "mega") {
            EXPECT_EQ(megaLayoutName(megaLayout(o)), v.variant.name) << v.name;
        } else if (v.name == "queue-padded") {
            EXPECT_EQ(queueGroup(o), 64);
            EXPECT_EQ(queueLocalPad(o), 16384u);
        } else if (v.pipeline != "persist") {
            EXPECT_EQ(v.name, v.pipeline);
        }
    }
    EXPECT_EQ(std::count(names.begin(), names.end(), "mega-tree"), 1) << names.size();
    EXPECT_EQ(std::count(names.begin(), names.end(), "mega-weighted"), 1) << names.size();
    EXPECT_EQ(std::count(names.begin(), names.end(), "wave"), 1) << names.size();
    EXPECT_EQ(std::count(names.begin(), names.end(), "queue"), 1) << names.size();
    EXPECT_EQ(std::count(names.begin(), names.end(), "queue-padded"), 1) << names.size();
    for (const char* persist : {"persist", "persist-regrouped", "persist-nested", "persist-bounce",
                                "persist-bounce-staged", "persist-auto"})
        EXPECT_EQ(std::count(names.begin(), names.end(), persist), 1) << persist;
    EXPECT_EQ(std::count(names.begin(), names.end(), "cpu"), 0) << "devices only";
}

// Keys written while the layout was a field of every cell ("|0" tree, "|1" weighted after the
// accel) lose the field and gain the megakernel's tag where weighted; today's keys pass unchanged.
TEST(Registry, OldCellKeysTranslateToTodays) {
    EXPECT_EQ(bench::currentCellKey("mega|spheres|640x360|5|1|1|bv|1|0|0|L100"),
              "mega|spheres|640x360|5|1|1|bv|0|0|L100|Wweighted");
    EXPECT_EQ(bench::currentCellKey("mega|spheres|64x36|3|1|1|bv|1|0|1"),
              "mega|spheres|64x36|3|1|1|bv|0|1|Wweighted");
    EXPECT_EQ(bench::currentCellKey("queue|cornell|1920x1080|8|8|1|bvh|0|0|0|L100|Qdevice|P4096"),
              "queue|cornell|1920x1080|8|8|1|bvh|0|0|L100|Qdevice|P4096");
    EXPECT_EQ(bench::currentCellKey("wave|empty|320x240|3|1|1|-|0|33554432|0"),
              "wave|empty|320x240|3|1|1|-|33554432|0");
    // The weighted layout's tag goes before the queue's: the megakernel registers first.
    EXPECT_EQ(bench::currentCellKey("mega|cornell|64x36|3|1|1|bvh|1|0|0|Qdevice"),
              "mega|cornell|64x36|3|1|1|bvh|0|0|Wweighted|Qdevice");
    for (const std::string today :
         {"mega|spheres|640x360|5|1|1|bv|0|0|L100|Wweighted", "wave|empty|320x240|3|1|1|-|0|1",
          "queue|cornell|1920x1080|8|8|1|bvh|0|0|L100|Qdevice|P4096",
          "mega|shadows|8x6|0|1|1|bv|0|0"})
        EXPECT_EQ(bench::currentCellKey(today), today);
    // And the cells of today make the keys it gives.
    bench::SweepConfig c = bench::parseSweep(
        "[a]\nscenes = spheres\npipelines = mega\nsizes = 64x36\nbounces = 3\nlayout = weighted\n"
        "[b]\nscenes = spheres\npipelines = mega\nsizes = 64x36\nbounces = 3\n",
        "t");
    Scene scene = loadScene("scenes/spheres.json", readImage);
    std::vector<bench::Cell> cells =
        bench::expandCells(c, [&](const std::string&) -> const Scene& { return scene; });
    ASSERT_EQ(cells.size(), 2u);
    const std::string accel = accelName(cells[0].options.accel);
    EXPECT_EQ(bench::currentCellKey("mega|spheres|64x36|3|" +
                                    std::to_string(cells[0].options.shadowSamples) + "|" +
                                    std::to_string(cells[0].options.aa) + "|" + accel + "|1|0|0"),
              cells[0].key());
    EXPECT_EQ(bench::currentCellKey("mega|spheres|64x36|3|" +
                                    std::to_string(cells[1].options.shadowSamples) + "|" +
                                    std::to_string(cells[1].options.aa) + "|" + accel + "|0|0|0"),
              cells[1].key());
}

TEST(Registry, DevicePipelineNeedsADevice) {
    for (const std::string& n : pipelineRegistry().names(true))
        EXPECT_THROW(makePipeline(n, nullptr), Error) << n;
}

}  // namespace
}  // namespace rt
