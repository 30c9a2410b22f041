// Scene files: every malformed file fails with its exact one-line message, and the standard
// scenes load with the objects, materials and settings they declare.
#include "core/scene_loader.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "core/accel.h"
#include "core/error.h"
#include "image/image_io.h"
#include "scratch_dir.h"

namespace rt {
namespace {

namespace fs = std::filesystem;
constexpr float kDeg = 3.14159265358979f / 180.f;

std::string loadError(const fs::path& path, const ImageReader& reader = {}) {
    try {
        loadScene(path, reader);
    } catch (const Error& e) {
        return e.what();
    }
    return "(no error)";
}

// Writes `text` to a fresh file in a per-test folder of this process's scratch folder.
fs::path writeTemp(const std::string& name, const std::string& text) {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    fs::path dir = rt::test::scratchPath(std::string(info->name()) + "/");
    std::ofstream(dir / name) << text;
    return dir / name;
}

struct BadScene {
    const char* file;
    const char* message;  // after "tests/data/bad_scenes/<file>: "
};

const BadScene kBadScenes[] = {
    {"syntax_error.json",
     "line 4, column 33: syntax error while parsing object - unexpected string literal; "
     "expected '}'"},
    {"empty_file.json",
     "line 1, column 1: syntax error while parsing value - unexpected end of input; expected "
     "'[', '{', or a literal"},
    {"nan_literal.json",
     "line 2, column 47: syntax error while parsing value - invalid literal; last read: "
     "'\"radius\": N'"},
    {"number_overflow.json", "line 2, column 47: number overflow parsing '1e999'"},
    {"not_an_object.json", "/: must be an object, got array"},
    {"missing_camera.json", "/: missing required key 'camera'"},
    {"missing_camera_position.json", "/camera: missing required key 'position'"},
    {"fov_out_of_range.json", "/camera/fov: must be in (0, 180) degrees, got 180"},
    {"look_at_and_yaw.json", "/camera: give either 'look_at' or 'yaw'/'pitch'"},
    {"wrong_type.json", "/spheres/0/radius: must be a number, got string"},
    {"negative_radius.json", "/spheres/2/radius: must be > 0, got -1"},
    {"short_vector.json", "/spheres/0/center: must be an array of 3 numbers, got an array of 2"},
    {"huge_value.json", "/spheres/0/center/0: must be a finite 32-bit float, got 1e+39"},
    {"unknown_material.json",
     "/spheres/0/material: unknown material 'glas' (did you mean 'glass'?)"},
    {"unknown_key.json", "/spheres/0: unknown key 'radus' (did you mean 'radius'?)"},
    {"duplicate_material.json", "/materials: duplicate key 'red'"},
    {"opacity_out_of_range.json", "/materials/glass/opacity: must be in [0, 1], got 1.5"},
    {"zero_ior.json", "/materials/glass/ior: must be > 0, got 0"},
    {"negative_color.json", "/materials/red/diffuse/1: must be >= 0, got -0.1"},
    {"zero_plane_normal.json", "/planes/0/normal: must be a non-zero vector"},
    {"plane_offset_and_point.json", "/planes/0: give either 'offset' or 'point', not both"},
    {"degenerate_triangle.json", "/triangles/0/vertices: degenerate triangle (zero area)"},
    {"triangle_two_vertices.json", "/triangles/0/vertices: must be an array of 3 vertices, got 2"},
    {"missing_obj.json",
     "/meshes/0/file: tests/data/bad_scenes/no_such_model.obj: cannot open: No such file or "
     "directory"},
    {"broken_obj.json",
     "/meshes/0/file: tests/data/bad_scenes/../bad_obj/index_out_of_range.obj: line 5: vertex "
     "index 9 out of range (3 vertices in the file)"},
    {"zero_scale.json", "/meshes/0/transform/scale: must be non-zero"},
    {"unknown_transform_key.json",
     "/meshes/0/transform: unknown key 'rotation' (did you mean 'rotate'?)"},
    {"too_many_lights.json", "/lights: at most 16 lights, got 17"},
    {"negative_light_radius.json", "/lights/0/radius: must be >= 0, got -0.5"},
    {"cubemap_five_faces.json",
     "/environment/cubemap: must list 6 faces (+x, -x, +y, -y, +z, -z), got 5"},
    {"cubemap_no_reader.json", "/environment/cubemap: cubemap needs an image reader"},
    {"sky_and_cubemap.json", "/environment: give either 'sky' or 'cubemap', not both"},
    {"bounces_out_of_range.json", "/render/bounces: must be in 0..16, got 17"},
    {"shadow_samples_zero.json", "/render/shadow_samples: must be in 1..255, got 0"},
    {"fractional_aa.json", "/render/aa: must be an integer, got 2.5"},
    {"adaptive_not_bool.json", "/render/adaptive_aa: must be true or false, got string"},
};

class BadSceneTest : public ::testing::TestWithParam<BadScene> {};

TEST_P(BadSceneTest, FailsWithExactOneLineMessage) {
    const std::string path = std::string("tests/data/bad_scenes/") + GetParam().file;
    const std::string message = loadError(path);
    EXPECT_EQ(message, path + ": " + GetParam().message);
    EXPECT_EQ(message.find('\n'), std::string::npos);
}

INSTANTIATE_TEST_SUITE_P(AllFiles, BadSceneTest, ::testing::ValuesIn(kBadScenes),
                         [](const auto& info) {
                             std::string name = info.param.file;
                             return name.substr(0, name.find('.'));
                         });

TEST(SceneLoader, EveryBadSceneFileIsInTheTable) {
    int files = 0;
    for (const auto& entry : fs::directory_iterator("tests/data/bad_scenes")) {
        if (entry.path().extension() != ".json") continue;
        ++files;
        bool listed = false;
        for (const BadScene& b : kBadScenes) listed |= entry.path().filename() == b.file;
        EXPECT_TRUE(listed) << entry.path() << " has no expected message";
    }
    EXPECT_EQ(files, int(std::size(kBadScenes)));
}

TEST(SceneLoader, MissingFileNamesTheFileAndTheReason) {
    EXPECT_EQ(loadError("tests/data/no_such_scene.json"),
              "tests/data/no_such_scene.json: cannot open: No such file or directory");
    EXPECT_EQ(loadError("tests/data/no_such_model.obj"),
              "tests/data/no_such_model.obj: cannot open: No such file or directory");
}

TEST(SceneLoader, SpheresSceneHasPhongMirrorAndGlassLineUp) {
    Scene s = loadScene("scenes/spheres.json");
    EXPECT_EQ(s.name, "spheres");
    EXPECT_EQ(s.source, fs::path("scenes/spheres.json"));
    EXPECT_EQ(s.spheres.size(), 10u);
    EXPECT_EQ(s.planes.size(), 1u);
    EXPECT_EQ(s.lights.size(), 2u);
    EXPECT_TRUE(s.triangles.empty());
    ASSERT_EQ(s.materials.size(), 11u);
    ASSERT_EQ(s.materialNames.size(), 11u);
    EXPECT_EQ(s.materialNames[0], "ground");  // file order, not alphabetical
    EXPECT_EQ(s.materialNames[1], "phong");
    EXPECT_EQ(s.materialNames[2], "mirror");
    for (int k = 0; k < 8; ++k) {
        const dev::Material& glass = s.materials[3 + k];
        EXPECT_EQ(s.materialNames[3 + k], "glass1" + std::to_string(k));
        EXPECT_NEAR(glass.ior, 1.0f + 0.1f * k, 1e-6f);
        EXPECT_EQ(glass.opacity, 0.f);
        EXPECT_EQ(s.spheres[2 + k].material, 3 + k);
    }
    EXPECT_EQ(s.branching(), 2);
    EXPECT_TRUE(s.hasTransparency());
    EXPECT_EQ(s.planes[0].normal.y, 1.f);
}

TEST(SceneLoader, ShadowsSceneHasHardAndSoftLight) {
    Scene s = loadScene("scenes/shadows.json");
    EXPECT_EQ(s.spheres.size(), 1u);
    EXPECT_EQ(s.planes.size(), 1u);
    ASSERT_EQ(s.lights.size(), 2u);
    EXPECT_EQ(s.lights[0].radius, 0.f);
    EXPECT_GT(s.lights[1].radius, 0.f);
    EXPECT_EQ(s.defaults.shadowSamples, 16);
    EXPECT_EQ(s.branching(), 1);
    EXPECT_FALSE(s.hasTransparency());
    // "point": [0, 0, 0] with normal +y gives offset 0.
    EXPECT_EQ(s.planes[0].offset, 0.f);
    EXPECT_NEAR(s.camera.pitch, -15 * kDeg, 1e-6f);
    EXPECT_NEAR(s.camera.fovY, 50 * kDeg, 1e-6f);
}

TEST(SceneLoader, CornellBoxIsTenTrianglesInOneImplicitMesh) {
    Scene s = loadScene("scenes/cornell.json");
    EXPECT_EQ(s.triangles.size(), 10u);
    ASSERT_EQ(s.meshes.size(), 1u);
    EXPECT_EQ(s.meshes[0].firstTriangle, 0);
    EXPECT_EQ(s.meshes[0].triangleCount, 10);
    EXPECT_EQ(s.meshes[0].bvhRoot, -1);
    EXPECT_EQ(s.meshes[0].boundsLo.x, -1.f);
    EXPECT_EQ(s.meshes[0].boundsHi.y, 2.f);
    EXPECT_EQ(s.meshes[0].boundsHi.z, 2.f);
    EXPECT_NEAR(s.meshes[0].sphereRadius, std::sqrt(3.f), 1e-5f);
    EXPECT_EQ(s.spheres.size(), 2u);
    EXPECT_EQ(s.lights.size(), 1u);
    EXPECT_EQ(s.branching(), 2);
    for (const dev::Triangle& t : s.triangles) {
        EXPECT_EQ(t.mesh, 0);
        // Without file normals every corner carries the unit face normal.
        EXPECT_NEAR(t.n0.x * t.n0.x + t.n0.y * t.n0.y + t.n0.z * t.n0.z, 1.f, 1e-6f);
        EXPECT_EQ(t.n0.x, t.n2.x);
    }
    // Floor normals point up into the box.
    EXPECT_EQ(s.triangles[0].n0.y, 1.f);
}

TEST(SceneLoader, MeshSceneLoadsTheKnotTransformed) {
    Scene s = loadScene("scenes/mesh.json");
    ASSERT_EQ(s.meshes.size(), 1u);
    EXPECT_GE(s.triangles.size(), 10000u);
    EXPECT_EQ(s.meshes[0].triangleCount, int(s.triangles.size()));
    EXPECT_EQ(s.planes.size(), 1u);
    EXPECT_EQ(s.branching(), 1);
    // Translated to (0, 1.8, 5); the knot is about 3.2 wide and 1.2 deep.
    const dev::MeshInstance& m = s.meshes[0];
    EXPECT_NEAR(m.sphereCenter.y, 1.8f, 0.2f);
    EXPECT_NEAR(m.sphereCenter.z, 5.f, 0.3f);
    EXPECT_GT(m.boundsLo.y, 0.f);  // above the ground plane
    EXPECT_GT(m.sphereRadius, 1.4f);
    EXPECT_LT(m.sphereRadius, 2.0f);
    for (const dev::Triangle& t : s.triangles) {
        ASSERT_GE(t.v0.y, m.boundsLo.y);
        ASSERT_LE(t.v0.y, m.boundsHi.y);
    }
    // look_at (0, 1.8, 5) from (0, 2, -2): straight ahead, slightly down.
    EXPECT_NEAR(s.camera.yaw, 0.f, 1e-6f);
    EXPECT_NEAR(s.camera.pitch, std::atan2(-0.2f, 7.f), 1e-5f);
}

TEST(SceneLoader, EmptySceneHasOnlySky) {
    Scene s = loadScene("scenes/empty.json");
    EXPECT_TRUE(s.spheres.empty() && s.planes.empty() && s.triangles.empty());
    EXPECT_TRUE(s.meshes.empty() && s.lights.empty() && s.materials.empty());
    EXPECT_EQ(s.environment.cubemapSize, 0);
    EXPECT_EQ(s.environment.zenith.x, 0.2f);
    EXPECT_EQ(s.branching(), 1);
}

TEST(SceneLoader, EnvmapSceneReadsSixFaces) {
    Scene s = loadScene("scenes/envmap.json", readImage);
    EXPECT_EQ(s.environment.cubemapSize, 64);
    EXPECT_EQ(s.environment.cubemap.size(), 6u * 64 * 64 * 3);
    EXPECT_EQ(s.spheres.size(), 2u);
    EXPECT_EQ(s.branching(), 2);
    // Face +x is a red checkerboard: red dominates its first texel.
    EXPECT_GT(s.environment.cubemap[0], 2 * s.environment.cubemap[1]);
}

TEST(SceneLoader, DefaultsFillEveryOptionalKey) {
    fs::path p = writeTemp("minimal.json", R"({
        "camera": {"position": [1, 2, 3]},
        "materials": {"m": {}},
        "spheres": [{"center": [0, 0, 5], "radius": 1, "material": "m"}],
        "lights": [{"position": [0, 5, 0]}]
    })");
    Scene s = loadScene(p);
    EXPECT_EQ(s.name, "minimal");
    EXPECT_EQ(s.camera.position.z, 3.f);
    EXPECT_EQ(s.camera.yaw, 0.f);
    EXPECT_EQ(s.camera.pitch, 0.f);
    EXPECT_NEAR(s.camera.fovY, 45 * kDeg, 1e-6f);
    const dev::Material& m = s.materials[0];
    EXPECT_EQ(m.diffuse.y, 0.8f);
    EXPECT_EQ(m.ambient.x, 0.f);
    EXPECT_EQ(m.specular.z, 0.f);
    EXPECT_EQ(m.exponent, 32.f);
    EXPECT_EQ(m.reflectance, 0.f);
    EXPECT_EQ(m.opacity, 1.f);
    EXPECT_EQ(m.ior, 1.f);
    EXPECT_EQ(s.lights[0].radius, 0.f);
    EXPECT_EQ(s.lights[0].color.y, 1.f);
    const RenderOptions defaults;
    EXPECT_EQ(s.defaults.width, defaults.width);
    EXPECT_EQ(s.defaults.height, defaults.height);
    EXPECT_EQ(s.defaults.bounces, defaults.bounces);
    EXPECT_EQ(s.defaults.shadowSamples, defaults.shadowSamples);
    EXPECT_EQ(s.defaults.aa, defaults.aa);
    EXPECT_EQ(s.defaults.adaptiveAa, false);
    EXPECT_EQ(s.environment.zenith.z, Environment().zenith.z);
}

TEST(SceneLoader, RenderSectionAndAnglesParse) {
    fs::path p = writeTemp("render.json", R"({
        "camera": {"position": [0, 0, 0], "yaw": 30, "pitch": -20, "fov": 60},
        "render": {"width": 64, "height": 48, "bounces": 16, "shadow_samples": 255,
                   "aa": 4.0, "shadow_strength": 0.5, "adaptive_aa": true}
    })");
    Scene s = loadScene(p);
    EXPECT_NEAR(s.camera.yaw, 30 * kDeg, 1e-6f);
    EXPECT_NEAR(s.camera.pitch, -20 * kDeg, 1e-6f);
    EXPECT_NEAR(s.camera.fovY, 60 * kDeg, 1e-6f);
    EXPECT_EQ(s.defaults.width, 64);
    EXPECT_EQ(s.defaults.height, 48);
    EXPECT_EQ(s.defaults.bounces, 16);
    EXPECT_EQ(s.defaults.shadowSamples, 255);
    EXPECT_EQ(s.defaults.aa, 4);
    EXPECT_EQ(s.defaults.shadowStrength, 0.5f);
    EXPECT_TRUE(s.defaults.adaptiveAa);
}

// Every structure --accel knows is a scene's render.accel too, and an unknown one is named.
TEST(SceneLoader, RenderAccelNamesEveryStructure) {
    for (const char* name : {"none", "bv", "grid", "bvh", "wide", "cwbvh"}) {
        fs::path p =
            writeTemp(std::string(name) + ".json",
                      std::string(R"({"camera": {"position": [0, 0, 0]}, "render": {"accel": ")") +
                          name + "\"}}");
        EXPECT_STREQ(accelName(loadScene(p).defaults.accel), name);
    }
    fs::path bad = writeTemp(
        "octree.json", R"({"camera": {"position": [0, 0, 0]}, "render": {"accel": "octree"}})");
    EXPECT_NE(loadError(bad).find("/render/accel: must be one of none, bv, grid, bvh, wide, cwbvh, "
                                  "got 'octree'"),
              std::string::npos)
        << loadError(bad);
}

TEST(SceneLoader, LookAtTurnsTowardTheTarget) {
    fs::path p =
        writeTemp("look.json", R"({"camera": {"position": [0, 0, 0], "look_at": [1, 0, 1]}})");
    Scene s = loadScene(p);
    EXPECT_NEAR(s.camera.yaw, 45 * kDeg, 1e-6f);  // positive yaw turns toward +x
    EXPECT_NEAR(s.camera.pitch, 0.f, 1e-6f);
    p = writeTemp("up.json", R"({"camera": {"position": [0, 0, 0], "look_at": [0, 1, 1]}})");
    EXPECT_NEAR(loadScene(p).camera.pitch, 45 * kDeg, 1e-6f);  // positive pitch looks up
}

TEST(SceneLoader, PlaneNormalIsNormalizedAndPointGivesOffset) {
    fs::path p = writeTemp("plane.json", R"({"camera": {"position": [0, 0, 0]},
        "materials": {"m": {}},
        "planes": [{"normal": [0, 3, 4], "point": [0, 1, 2], "material": "m"}]})");
    Scene s = loadScene(p);
    ASSERT_EQ(s.planes.size(), 1u);
    EXPECT_NEAR(s.planes[0].normal.y, 0.6f, 1e-6f);
    EXPECT_NEAR(s.planes[0].normal.z, 0.8f, 1e-6f);
    EXPECT_NEAR(s.planes[0].offset, 0.6f + 1.6f, 1e-6f);
}

TEST(SceneLoader, CommentsAreAllowed) {
    fs::path p = writeTemp("comments.json",
                           "// a camera\n{\"camera\": {\"position\": [0, 0, 0] /* origin */}}");
    EXPECT_EQ(loadScene(p).camera.position.x, 0.f);
}

TEST(SceneLoader, CubemapThroughInjectedReader) {
    fs::path p = writeTemp("cube.json", R"({"camera": {"position": [0, 0, 0]},
        "environment": {"cubemap": ["a.png", "b.png", "c.png", "d.png", "e.png", "f.png"]}})");
    int calls = 0;
    Scene s = loadScene(p, [&](const fs::path& face) {
        EXPECT_EQ(face, p.parent_path() / std::string(1, char('a' + calls)).append(".png"));
        Image img(8, 8);
        img.rgb.assign(img.rgb.size(), float(calls++));
        return img;
    });
    EXPECT_EQ(calls, 6);
    EXPECT_EQ(s.environment.cubemapSize, 8);
    ASSERT_EQ(s.environment.cubemap.size(), 6u * 8 * 8 * 3);
    EXPECT_EQ(s.environment.cubemap[0], 0.f);
    EXPECT_EQ(s.environment.cubemap.back(), 5.f);  // faces in file order

    auto sized = [](int w, int h, int odd) {
        return
            [=, n = 0](const fs::path&) mutable { return n++ == odd ? Image(w, h) : Image(8, 8); };
    };
    EXPECT_EQ(loadError(p, sized(8, 4, 2)),
              p.string() + ": /environment/cubemap/2: face is 8x4, must be square");
    EXPECT_EQ(loadError(p, sized(16, 16, 5)),
              p.string() + ": /environment/cubemap/5: face is 16x16, but face 0 is 8x8");
    EXPECT_EQ(
        loadError(p, [](const fs::path& f) -> Image { throw Error(f.string() + ": bad png"); }),
        p.string() + ": /environment/cubemap/0: " + (p.parent_path() / "a.png").string() +
            ": bad png");
}

TEST(SceneLoader, MaterialLimitIs65535) {
    std::ostringstream json;
    json << R"({"camera": {"position": [0, 0, 0]}, "materials": {)";
    for (int i = 0; i < 65536; ++i) json << (i ? "," : "") << "\"m" << i << "\":{}";
    json << "}}";
    fs::path p = writeTemp("many.json", json.str());
    EXPECT_EQ(loadError(p), p.string() + ": /materials: too many materials: 65536 (at most 65535)");
}

// A 4 px mesh wall of the crossover map (scripts/make-map.py --shape mesh) places 129,600 meshes,
// each with its own material; the model file is parsed once.
TEST(SceneLoader, AWallOfSmallMeshesKeepsEachObjectsMaterial) {
    writeTemp("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const int n = 129'600;
    std::ostringstream json;
    json << R"({"camera": {"position": [0, 0, -5]}, "materials": {"a": {}, "b": {}, "c": {}},)"
         << R"("meshes": [)";
    for (int i = 0; i < n; ++i)
        json << (i ? "," : "") << R"({"file": "tri.obj", "material": ")"
             << "abc"[i % 3] << R"(", "transform": {"translate": [)" << i % 480 << ", " << i / 480
             << R"(, 0], "scale": 0.5}})";
    json << "]}";
    Scene s = loadScene(writeTemp("wall.json", json.str()));
    ASSERT_EQ(s.meshes.size(), std::size_t(n));
    ASSERT_EQ(s.triangles.size(), std::size_t(n));
    for (int i : {0, 1, 2, 12'345, n - 1}) {
        EXPECT_EQ(s.materialNames[s.triangles[i].material], std::string(1, "abc"[i % 3])) << i;
        EXPECT_EQ(s.triangles[i].mesh, i);
        EXPECT_FLOAT_EQ(s.triangles[i].v1.x, float(i % 480) + 0.5f) << i;
    }
}

TEST(SceneLoader, ReadmeExampleLoads) {
    std::ifstream in("scenes/README.md");
    std::string readme((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::size_t begin = readme.find("```json\n");
    ASSERT_NE(begin, std::string::npos);
    begin += 8;
    std::string example = readme.substr(begin, readme.find("```", begin) - begin);
    const std::string model = "\"models/knot.obj\"";
    example.replace(example.find(model), model.size(),
                    "\"" + fs::absolute("scenes/models/knot.obj").string() + "\"");
    Scene s = loadScene(writeTemp("example.json", example));
    EXPECT_EQ(s.materials.size(), 4u);
    EXPECT_EQ(s.spheres.size(), 1u);
    EXPECT_EQ(s.planes.size(), 1u);
    EXPECT_EQ(s.meshes.size(), 2u);  // the loose triangles, then the knot
    EXPECT_EQ(s.meshes[0].triangleCount, 2);
    EXPECT_EQ(s.meshes[1].firstTriangle, 2);
    EXPECT_EQ(s.lights.size(), 2u);
    EXPECT_EQ(s.defaults.aa, 2);
    EXPECT_EQ(s.branching(), 2);
}

TEST(SceneLoader, BareObjGetsADefaultScene) {
    Scene s = loadScene("tests/data/cube.obj");
    EXPECT_EQ(s.name, "cube");
    EXPECT_EQ(s.triangles.size(), 12u);
    ASSERT_EQ(s.meshes.size(), 1u);
    ASSERT_EQ(s.materialNames.size(), 2u);
    EXPECT_EQ(s.materialNames[0], "default");
    EXPECT_EQ(s.materials[0].diffuse.x, 0.7f);
    EXPECT_EQ(s.triangles[0].material, 0);
    ASSERT_EQ(s.planes.size(), 1u);
    EXPECT_EQ(s.planes[0].normal.y, 1.f);
    EXPECT_EQ(s.planes[0].material, 1);
    EXPECT_LT(s.planes[0].offset, -0.5f);  // just below the cube
    EXPECT_GT(s.planes[0].offset, -0.51f);
    ASSERT_EQ(s.lights.size(), 1u);
    EXPECT_GT(s.lights[0].position.y, 0.5f);   // above
    EXPECT_LT(s.lights[0].position.z, -0.5f);  // in front
    // Camera on -z looking along +z at the centre, the bounding sphere inside the 45-degree fov.
    EXPECT_EQ(s.camera.yaw, 0.f);
    EXPECT_EQ(s.camera.pitch, 0.f);
    EXPECT_NEAR(s.camera.fovY, 45 * kDeg, 1e-6f);
    EXPECT_EQ(s.camera.position.x, 0.f);
    EXPECT_EQ(s.camera.position.y, 0.f);
    const float r = std::sqrt(0.75f);
    EXPECT_LT(s.camera.position.z, -r / std::sin(22.5f * kDeg));
    EXPECT_EQ(s.branching(), 1);
}

TEST(SceneLoader, BareObjErrorsNameTheObj) {
    EXPECT_EQ(loadError("tests/data/bad_obj/empty.obj"),
              "tests/data/bad_obj/empty.obj: no triangles");
}

TEST(FinalizeScene, ComputesBoundsAndAssignsMeshes) {
    Scene s;
    s.name = "hand";
    s.materials.push_back({});
    auto tri = [](float x) {
        return dev::Triangle{{x, 0, 0}, {x + 1, 0, 0}, {x, 2, 0}, {}, {}, {}, 0, 7};
    };
    s.triangles = {tri(0), tri(4), tri(10)};
    s.meshes = {{0, 2, 5, 0, {}, {}, {}, 0.f, {}}, {2, 1, 5, 0, {}, {}, {}, 0.f, {}}};
    finalizeScene(s);
    EXPECT_EQ(s.triangles[0].mesh, 0);
    EXPECT_EQ(s.triangles[1].mesh, 0);
    EXPECT_EQ(s.triangles[2].mesh, 1);
    const dev::MeshInstance& m = s.meshes[0];
    EXPECT_EQ(m.bvhRoot, -1);
    EXPECT_EQ(m.boundsLo.x, 0.f);
    EXPECT_EQ(m.boundsHi.x, 5.f);
    EXPECT_EQ(m.boundsHi.y, 2.f);
    EXPECT_EQ(m.sphereCenter.x, 2.5f);
    EXPECT_EQ(m.sphereCenter.y, 1.f);
    // Farthest vertices from (2.5, 1, 0): (0, 0), (5, 0), (0, 2), (4, 2)... at sqrt(2.5^2 + 1).
    EXPECT_NEAR(m.sphereRadius, std::sqrt(7.25f), 1e-6f);
    EXPECT_EQ(s.meshes[1].boundsLo.x, 10.f);
}

TEST(FinalizeScene, LooseTrianglesGetOneMesh) {
    Scene s;
    s.materials.push_back({});
    s.triangles = {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {}, {}, {}, 0, 0}};
    finalizeScene(s);
    ASSERT_EQ(s.meshes.size(), 1u);
    EXPECT_EQ(s.meshes[0].triangleCount, 1);
}

TEST(FinalizeScene, RejectsNanVerticesAndBadMeshes) {
    Scene s;
    s.name = "hand";
    s.materials.push_back({});
    s.triangles = {{{0, 0, 0}, {NAN, 0, 0}, {0, 1, 0}, {}, {}, {}, 0, 0}};
    try {
        finalizeScene(s);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(), "hand: triangle 0 has a non-finite vertex");
    }
    s.triangles[0].v1.x = 1.f;
    s.meshes = {{0, 2, -1, 0, {}, {}, {}, 0.f, {}}};
    EXPECT_THROW(finalizeScene(s), Error);  // covers a triangle that does not exist
    s.meshes = {{0, 1, -1, 0, {}, {}, {}, 0.f, {}}};
    s.triangles[0].material = 3;
    EXPECT_THROW(finalizeScene(s), Error);  // material out of range
}

TEST(TreeNodeCount, MatchesTheHeapFormula) {
    EXPECT_EQ(treeNodeCount(1, 0), 1);
    EXPECT_EQ(treeNodeCount(1, 3), 4);
    EXPECT_EQ(treeNodeCount(2, 0), 1);
    EXPECT_EQ(treeNodeCount(2, 3), 15);
    EXPECT_EQ(treeNodeCount(2, 16), 131071);
    Scene spheres = loadScene("scenes/spheres.json");
    EXPECT_EQ(treeNodeCount(spheres.branching(), spheres.defaults.bounces), 31);
}

}  // namespace
}  // namespace rt
