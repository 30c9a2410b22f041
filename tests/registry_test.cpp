// The pipeline registry (issue 13): front ends see pipelines only through it, so it must list the
// CPU reference first and every pipeline folder once, refuse a second entry under one name, and
// name every choice when asked for one it lacks.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "core/error.h"
#include "pipelines/registry.h"
#include "test_device.h"

namespace rt {
namespace {

TEST(Registry, ListsTheReferenceFirstAndEveryPipelineOnce) {
    const PipelineRegistry& r = pipelineRegistry();
    ASSERT_GE(r.all().size(), 3u);
    EXPECT_TRUE(r.all()[0].reference);
    std::set<std::string> seen;
    for (const PipelineInfo& p : r.all()) {
        EXPECT_TRUE(seen.insert(p.name).second) << p.name;
        EXPECT_FALSE(p.title.empty()) << p.name;
        EXPECT_FALSE(p.description.empty()) << p.name;
        EXPECT_EQ(p.reference, &p == &r.all()[0]) << "one reference, listed first: " << p.name;
    }
    // The two the project began with stay registered under their sweep-row names.
    EXPECT_NE(r.find("mega"), nullptr);
    EXPECT_NE(r.find("wave"), nullptr);
    EXPECT_EQ(r.names(true).size(), r.all().size() - 1);
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

TEST(Registry, DevicePipelineNeedsADevice) {
    for (const std::string& n : pipelineRegistry().names(true))
        EXPECT_THROW(makePipeline(n, nullptr), Error) << n;
}

}  // namespace
}  // namespace rt
