// OBJ models: broken files fail with their exact one-line message and never crash; good ones
// triangulate into the expected count with unit, outward normals.
#include "core/obj_loader.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <glm/glm.hpp>
#include <string>

#include "core/error.h"
#include "core/scene_loader.h"
#include "scratch_dir.h"
#include "tests/test_device.h"

namespace rt {
namespace {

namespace fs = std::filesystem;

std::string objLoadError(const fs::path& path) {
    try {
        loadObj(path);
    } catch (const Error& e) {
        return e.what();
    }
    return "(no error)";
}

struct BadObj {
    const char* file;
    const char* message;  // after "tests/data/bad_obj/<file>: "
};

const BadObj kBadObjs[] = {
    {"empty.obj", "no triangles"},
    {"only_vertices.obj", "no triangles"},
    {"index_out_of_range.obj", "line 5: vertex index 9 out of range (3 vertices in the file)"},
    {"missing_vertex.obj", "line 4: face has 2 vertices, needs at least 3"},
    {"non_numeric.obj", "line 2: bad number 'abc'"},
    {"nan_coordinate.obj", "line 1: bad number 'nan'"},
    {"float_overflow.obj", "line 1: coordinate '1e39' is not a finite 32-bit float"},
    {"truncated_vertex.obj", "line 3: vertex needs 3 coordinates, got 2"},
    {"truncated_face.obj", "line 5: bad face corner '1/'"},
    {"zero_index.obj", "line 4: vertex index 0 in '0' (OBJ indices start at 1)"},
    {"huge_index.obj", "line 4: vertex index '99999999999999999999' out of range"},
    {"negative_beyond_start.obj",
     "line 4: vertex index -5 reaches before the first vertex (3 defined so far)"},
    {"normal_out_of_range.obj", "line 5: normal index 2 out of range (1 normal in the file)"},
    {"bad_corner.obj", "line 4: bad face corner '1/1/1/1'"},
    {"degenerate_only.obj", "all 2 triangles are degenerate (zero area)"},
    {"binary_junk.obj", "binary data (NUL byte at offset 7), not a text OBJ file"},
    {"utf16.obj", "UTF-16 text is not supported; save the file as UTF-8"},
};

class BadObjTest : public ::testing::TestWithParam<BadObj> {};

TEST_P(BadObjTest, FailsWithExactOneLineMessage) {
    const std::string path = std::string("tests/data/bad_obj/") + GetParam().file;
    const std::string message = objLoadError(path);
    EXPECT_EQ(message, path + ": " + GetParam().message);
    EXPECT_EQ(message.find('\n'), std::string::npos);
}

INSTANTIATE_TEST_SUITE_P(AllFiles, BadObjTest, ::testing::ValuesIn(kBadObjs), [](const auto& info) {
    std::string name = info.param.file;
    return name.substr(0, name.find('.'));
});

TEST(ObjLoader, EveryBadObjFileIsInTheTable) {
    int files = 0;
    for (const auto& entry : fs::directory_iterator("tests/data/bad_obj")) {
        ++files;
        bool listed = false;
        for (const BadObj& b : kBadObjs) listed |= entry.path().filename() == b.file;
        EXPECT_TRUE(listed) << entry.path() << " has no expected message";
    }
    EXPECT_EQ(files, int(std::size(kBadObjs)));
}

TEST(ObjLoader, MissingFile) {
    EXPECT_EQ(objLoadError("tests/data/nope.obj"),
              "tests/data/nope.obj: cannot open: No such file or directory");
    EXPECT_EQ(objLoadError("tests/data"), "tests/data: cannot open: Is a directory");
}

TEST(ObjLoader, QuadAndPentagonTriangulate) {
    ObjMesh mesh = loadObj("tests/data/polygons.obj");
    ASSERT_EQ(mesh.positions.size(), 3u * 6);  // 1 + 2 + 3 triangles
    ASSERT_EQ(mesh.normals.size(), mesh.positions.size());
    // All in the z = 0 plane: every computed normal is +-z, and one orientation throughout.
    for (const glm::vec3& n : mesh.normals) EXPECT_NEAR(std::abs(n.z), 1.f, 1e-6f);
    for (const glm::vec3& n : mesh.normals) EXPECT_EQ(n.z, mesh.normals[0].z);
    // Triangulation keeps the area: 0.5 + 1 + pentagon.
    float area = 0.f;
    for (std::size_t t = 0; t < mesh.positions.size(); t += 3)
        area += 0.5f * glm::length(glm::cross(mesh.positions[t + 1] - mesh.positions[t],
                                              mesh.positions[t + 2] - mesh.positions[t]));
    // Pentagon (4,0) (5,0) (5.5,0.8) (4.5,1.5) (3.7,0.8), by the shoelace formula: 1.75.
    EXPECT_NEAR(area, 0.5f + 1.f + 1.75f, 1e-4f);
}

TEST(ObjLoader, ComputedNormalsAreUnitAndOutwardOnAClosedCube) {
    ObjMesh mesh = loadObj("tests/data/cube.obj");
    ASSERT_EQ(mesh.positions.size(), 3u * 12);
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
        EXPECT_NEAR(glm::length(mesh.normals[i]), 1.f, 1e-6f);
        // Smooth corner normals of a cube centred on the origin point away from it...
        EXPECT_GT(glm::dot(mesh.normals[i], mesh.positions[i]), 0.2f) << "corner " << i;
    }
    // ... and agree with the winding (counter-clockwise seen from outside).
    for (std::size_t t = 0; t < mesh.positions.size(); t += 3) {
        glm::vec3 face = glm::cross(mesh.positions[t + 1] - mesh.positions[t],
                                    mesh.positions[t + 2] - mesh.positions[t]);
        EXPECT_GT(glm::dot(face, mesh.normals[t]), 0.f);
    }
    // One position gets one normal, however many triangles share it.
    for (std::size_t i = 0; i < mesh.positions.size(); ++i)
        for (std::size_t j = 0; j < mesh.positions.size(); ++j)
            if (mesh.positions[i] == mesh.positions[j]) ASSERT_EQ(mesh.normals[i], mesh.normals[j]);
}

TEST(ObjLoader, FileNormalsAreUsedAndNormalized) {
    ObjMesh mesh = loadObj("tests/data/cube_normals.obj");
    ASSERT_EQ(mesh.normals.size(), 6u);
    for (const glm::vec3& n : mesh.normals) EXPECT_EQ(n, glm::vec3(0, 0, 1));
}

TEST(ObjLoader, KnotModelHasTenThousandTrianglesWithFileNormals) {
    ObjMesh mesh = loadObj("scenes/models/knot.obj");
    EXPECT_GE(mesh.positions.size() / 3, 10000u);
    EXPECT_EQ(mesh.positions.size() / 3, 12800u);
    for (const glm::vec3& n : mesh.normals) ASSERT_NEAR(glm::length(n), 1.f, 1e-5f);
    // Normals agree with the winding, so the tube is closed and oriented outward.
    int agree = 0;
    for (std::size_t t = 0; t < mesh.positions.size(); t += 3) {
        glm::vec3 face = glm::cross(mesh.positions[t + 1] - mesh.positions[t],
                                    mesh.positions[t + 2] - mesh.positions[t]);
        agree += glm::dot(face, mesh.normals[t]) > 0.f;
    }
    EXPECT_EQ(agree, int(mesh.positions.size() / 3));
}

// Real models ship with .mtl libraries: their Kd, Ks, Ns, Ni, d and illum become rtlab materials
// (scenes/README.md), faces without a known material keep the default.
TEST(ObjLoader, MtlMaterialsMapOntoRtlabMaterials) {
    const Scene scene = loadScene("tests/data/obj_mtl/two_materials.obj");
    EXPECT_TRUE(scene.notes.empty());
    ASSERT_EQ(scene.materials.size(), 4u);  // default, ground, then the file's two
    EXPECT_EQ(scene.materialNames[2], "red_mirror");
    EXPECT_EQ(scene.materialNames[3], "glass");
    ASSERT_EQ(scene.triangles.size(), 5u);  // two quads and a triangle
    const int expected[] = {2, 2, 3, 3, 0};
    for (int t = 0; t < 5; ++t)
        EXPECT_EQ(scene.triangles[t].material, expected[t]) << "triangle " << t;

    const dev::Material& red = scene.materials[2];
    EXPECT_FLOAT_EQ(red.diffuse.x, 0.8f);
    EXPECT_FLOAT_EQ(red.diffuse.y, 0.1f);
    EXPECT_FLOAT_EQ(red.ambient.x, 0.1f);
    EXPECT_FLOAT_EQ(red.exponent, 64.f);
    EXPECT_FLOAT_EQ(red.reflectance, 0.6f);  // illum 3: a mirror weighted by mean(Ks)
    EXPECT_FLOAT_EQ(red.opacity, 1.f);
    EXPECT_FLOAT_EQ(red.ior, 1.f);

    const dev::Material& glass = scene.materials[3];
    EXPECT_FLOAT_EQ(glass.opacity, 0.25f);
    EXPECT_FLOAT_EQ(glass.ior, 1.5f);
    EXPECT_FLOAT_EQ(glass.reflectance, 1.f);
    EXPECT_EQ(scene.branching(), 2) << "a transparent material makes the tree binary";
}

TEST(ObjLoader, MissingMtlLibraryRendersWithTheDefaultMaterialAndSaysSo) {
    const Scene scene = loadScene("tests/data/obj_mtl/missing_library.obj");
    ASSERT_EQ(scene.materials.size(), 2u);
    for (const dev::Triangle& t : scene.triangles) EXPECT_EQ(t.material, 0);
    ASSERT_EQ(scene.notes.size(), 1u);
    EXPECT_NE(scene.notes[0].find("no_such_library.mtl"), std::string::npos) << scene.notes[0];
}

// A library that is a device or FIFO would be read forever: refused like a missing one.
TEST(ObjLoader, MtlLibraryThatIsNoRegularFileIsRefusedNotRead) {
    const fs::path dir = rt::test::scratchPath("mtl/");
    const fs::path obj = dir / "endless.obj";
    std::ofstream(obj) << "mtllib ../../../../../../../../dev/zero\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"
                          "usemtl x\nf 1 2 3\n";
    const Scene scene = loadScene(obj);
    ASSERT_EQ(scene.notes.size(), 1u);
    EXPECT_NE(scene.notes[0].find("not a readable file"), std::string::npos) << scene.notes[0];
    EXPECT_EQ(scene.triangles.at(0).material, 0);
    fs::remove_all(dir);
}

TEST(ObjLoader, OtherModelFormatsAreRefusedByName) {
    for (const char* file : {"model.fbx", "scene.DAE", "part.stl"}) {
        try {
            loadScene(file);
            ADD_FAILURE() << file << " loaded";
        } catch (const Error& e) {
            const std::string msg = e.what();
            EXPECT_NE(msg.find(file), std::string::npos) << msg;
            EXPECT_NE(msg.find("files are not supported; rtlab reads .obj, .gltf, .glb and .ply "
                               "models and .json and .nff scenes"),
                      std::string::npos)
                << msg;
        }
    }
}

TEST(ObjLoader, StanfordBunnyLoads) {
    const fs::path bunny = rt::test::sharedFile("models/bunny.obj");
    RTLAB_REQUIRE_FILE(bunny);
    ObjMesh mesh = loadObj(bunny);
    EXPECT_EQ(mesh.positions.size() / 3, 69630u);
    for (const glm::vec3& n : mesh.normals) ASSERT_NEAR(glm::length(n), 1.f, 1e-5f);
}

// The assimp corpus (scripts/setup installs it): valid files load, broken ones fail cleanly.
TEST(ObjLoader, AssimpCorpusLoadsOrFailsCleanly) {
    const fs::path dir = "/usr/share/assimp/models";
    RTLAB_REQUIRE_FILE(dir / "OBJ");  // assimp-testmodels, installed by scripts/setup
    struct Case {
        const char* file;
        int triangles;  // -1: must fail
    };
    const Case cases[] = {
        {"OBJ/box.obj", 12},
        {"OBJ/box_longline.obj", 244},
        {"OBJ/concave_polygon.obj", 44},
        {"OBJ/spider.obj", 1312},
        {"OBJ/WusonOBJ.obj", 3732},
        {"OBJ/testmixed.obj", 12},
        {"OBJ/box_without_lineending.obj", 12},
        {"OBJ/testline.obj", -1},
        {"OBJ/point_cloud.obj", -1},
        {"OBJ/box_UTF16BE.obj", -1},
        {"OBJ/number_formats.obj", -1},
        {"invalid/empty.obj", -1},
        {"invalid/malformed.obj", -1},
        {"invalid/malformed2.obj", -1},
    };
    for (const Case& c : cases) {
        if (c.triangles >= 0) {
            EXPECT_EQ(loadObj(dir / c.file).positions.size() / 3, std::size_t(c.triangles))
                << c.file;
        } else {
            std::string message = objLoadError(dir / c.file);
            EXPECT_EQ(message.rfind((dir / c.file).string() + ": ", 0), 0u) << message;
            EXPECT_EQ(message.find('\n'), std::string::npos) << message;
        }
    }
    EXPECT_EQ(objLoadError(dir / "invalid/malformed.obj"),
              (dir / "invalid/malformed.obj").string() +
                  ": line 23: vertex index 12 out of range (8 vertices in the file)");
    // Every other file in the corpus loads or fails with one line; none crashes.
    for (const char* sub : {"OBJ", "invalid"})
        for (const auto& entry : fs::directory_iterator(dir / sub))
            if (entry.path().extension() == ".obj") {
                std::string message = objLoadError(entry.path());
                EXPECT_EQ(message.find('\n'), std::string::npos) << message;
            }
}

}  // namespace
}  // namespace rt
