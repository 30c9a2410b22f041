// glTF 2.0 and PLY models through assimp (core/model_loader.cpp): node transforms, the material
// mapping, the camera and the lights of tests/data/models/scene.gltf (and its .glb twin), PLY
// vertex colours, models inside a JSON scene, the exact one-line errors of
// tests/data/bad_models, and known values of Debian's assimp-testmodels. tests/assimp_test.cpp
// walks every glTF2 and PLY file of that corpus.
//
// scene.gltf holds one triangle (0,0,0) (1,0,0) (0,1,0) placed by four nodes:
//   "red"    translate (2,0,0), scale 2                     material red (base 0.8 0.1 0.1,
//            metallic 0, roughness 0.5, emissive 0.1 0 0)
//   "group"  translate (0,0,5), rotate 90 degrees about +y, with the child
//   "mirror" translate (1,0,0)                              material mirror (base 0.9, metallic 1,
//                                                           roughness 0)
//   "blend"  translate (0,0,10)                             material blend (base 0.2 0.4 0.6,
//                                                           alpha 0.25, BLEND, roughness 1)
//   "glass"  translate (0,0,12)                             material glass (transmission 1)
// a perspective camera "eye" at (0,1,-10) turned 180 degrees about y (so it looks along +z),
// yfov 0.5, aspect ratio 2; point lights "lamp" at (0,10,0) (colour 1 0.5 0.25, intensity 20)
// and "fill" at (3,3,3) (white, intensity 5).
#include "core/model_loader.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <glm/glm.hpp>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/scene_loader.h"
#include "scratch_dir.h"
#include "tests/test_device.h"

// Under scripts/sanitize: the model reader process resets the crash signals to their default
// action, so that a crash inside assimp is reported as one (assimp_segfault.glb below); ASan
// keeps its own handlers unless user handlers are allowed.
extern "C" const char* __asan_default_options() { return "allow_user_segv_handler=1"; }

namespace rt {
namespace {

namespace fs = std::filesystem;

const fs::path kModels = "tests/data/models";
const fs::path kCorpus = "/usr/share/assimp/models";

std::string loadError(const fs::path& path) {
    try {
        loadModel(path);
    } catch (const Error& e) {
        return e.what();
    }
    return "(no error)";
}

void expectNear(const glm::vec3& got, const glm::vec3& want, const char* what, float eps = 1e-5f) {
    EXPECT_NEAR(got.x, want.x, eps) << what;
    EXPECT_NEAR(got.y, want.y, eps) << what;
    EXPECT_NEAR(got.z, want.z, eps) << what;
}

void expectNear(const dev::Float3& got, const glm::vec3& want, const char* what,
                float eps = 1e-5f) {
    expectNear(glm::vec3(got.x, got.y, got.z), want, what, eps);
}

struct Bounds {
    glm::vec3 lo{INFINITY}, hi{-INFINITY};
};

Bounds bounds(const Model& m) {
    Bounds b;
    for (const glm::vec3& p : m.positions) {
        b.lo = glm::min(b.lo, p);
        b.hi = glm::max(b.hi, p);
    }
    return b;
}

TEST(ModelLoader, GltfNodeTransformsPlaceEveryTriangle) {
    const Model m = loadModel(kModels / "scene.gltf");
    ASSERT_EQ(m.positions.size(), 4u * 3u);
    ASSERT_EQ(m.normals.size(), m.positions.size());
    // "red": scaled by 2, then moved by (2,0,0).
    expectNear(m.positions[0], {2, 0, 0}, "red v0");
    expectNear(m.positions[1], {4, 0, 0}, "red v1");
    expectNear(m.positions[2], {2, 2, 0}, "red v2");
    expectNear(m.normals[0], {0, 0, 1}, "red n0 (computed: the file has no normals)");
    // "mirror": (1,0,0) in its parent, which turns +x into -z and moves by (0,0,5).
    expectNear(m.positions[3], {0, 0, 4}, "mirror v0");
    expectNear(m.positions[4], {0, 0, 3}, "mirror v1");
    expectNear(m.positions[5], {0, 1, 4}, "mirror v2");
    expectNear(m.normals[3], {1, 0, 0}, "mirror n0 (rotated with it)");
    expectNear(m.positions[9], {0, 0, 12}, "glass v0");
    const Bounds b = bounds(m);
    expectNear(b.lo, {0, 0, 0}, "bounds lo");
    expectNear(b.hi, {4, 2, 12}, "bounds hi");
}

TEST(ModelLoader, GltfMaterialsMapOntoBlinnPhong) {
    const Model m = loadModel(kModels / "scene.gltf");
    ASSERT_EQ(m.materials.size(), 4u);
    EXPECT_EQ(m.materialNames, (std::vector<std::string>{"red", "mirror", "blend", "glass"}));
    EXPECT_EQ(m.triangleMaterial, (std::vector<int>{0, 1, 2, 3}));

    const dev::Material& red = m.materials[0];  // dielectric, roughness 0.5
    expectNear(red.diffuse, {0.8f, 0.1f, 0.1f}, "red diffuse = base");
    expectNear(red.specular, {0.02f, 0.02f, 0.02f}, "red specular = 0.04 (1 - roughness)");
    EXPECT_NEAR(red.exponent, 30.f, 1e-3f) << "2 / roughness^4 - 2";
    expectNear(red.ambient, {0.14f, 0.005f, 0.005f}, "red ambient = emissive + 0.05 diffuse");
    EXPECT_EQ(red.reflectance, 0.f);
    EXPECT_EQ(red.opacity, 1.f);

    const dev::Material& mirror = m.materials[1];  // smooth metal
    expectNear(mirror.diffuse, {0, 0, 0}, "mirror diffuse");
    expectNear(mirror.specular, {0.9f, 0.9f, 0.9f}, "mirror specular = base");
    EXPECT_EQ(mirror.exponent, 10000.f);
    EXPECT_EQ(mirror.reflectance, 1.f);

    const dev::Material& blend = m.materials[2];
    expectNear(blend.diffuse, {0.2f, 0.4f, 0.6f}, "blend diffuse");
    EXPECT_FLOAT_EQ(blend.opacity, 0.25f) << "BLEND: the base colour's alpha";
    EXPECT_EQ(blend.ior, 1.f) << "blending bends nothing";
    EXPECT_EQ(blend.exponent, 1.f) << "roughness 1";

    const dev::Material& glass = m.materials[3];
    EXPECT_EQ(glass.opacity, 0.f) << "transmission 1";
    EXPECT_FLOAT_EQ(glass.ior, 1.5f) << "glTF's default index of refraction";
    EXPECT_TRUE(m.notes.empty()) << m.notes.at(0);
}

TEST(ModelLoader, GltfCameraAndPointLights) {
    const Model m = loadModel(kModels / "scene.gltf");
    ASSERT_TRUE(m.camera.has_value());
    expectNear(m.camera->position, {0, 1, -10}, "camera at its node's origin");
    expectNear(m.camera->direction, {0, 0, 1}, "-z of a node turned 180 degrees about y");
    EXPECT_NEAR(m.camera->fovY, 0.5f, 1e-6f) << "yfov, not assimp's yfov * aspect ratio";
    ASSERT_EQ(m.lights.size(), 2u);
    expectNear(m.lights[0].position, {0, 10, 0}, "lamp");
    expectNear(m.lights[0].color, {1, 0.5f, 0.25f}, "lamp: the brightest channel becomes 1");
    expectNear(m.lights[1].position, {3, 3, 3}, "fill");
    expectNear(m.lights[1].color, {0.25f, 0.25f, 0.25f}, "fill: 5 / 20 of the lamp");
    EXPECT_EQ(m.lights[0].radius, 0.f);
}

TEST(ModelLoader, GlbHoldsTheSameScene) {
    const Model gltf = loadModel(kModels / "scene.gltf");
    const Model glb = loadModel(kModels / "scene.glb");
    ASSERT_EQ(glb.positions.size(), gltf.positions.size());
    for (std::size_t i = 0; i < glb.positions.size(); ++i)
        expectNear(glb.positions[i], gltf.positions[i], "same vertex");
    EXPECT_EQ(glb.materialNames, gltf.materialNames);
    ASSERT_TRUE(glb.camera.has_value());
    EXPECT_EQ(glb.lights.size(), 2u);
}

// rtlab render scene.gltf: the file's materials after default and ground, its camera as yaw and
// pitch, its lights instead of the default one, and the ground plane under the model.
TEST(ModelLoader, BareGltfSceneUsesTheFileCameraLightsAndMaterials) {
    const Scene s = loadScene(kModels / "scene.gltf");
    EXPECT_EQ(s.name, "scene");
    EXPECT_EQ(s.materialNames,
              (std::vector<std::string>{"default", "ground", "red", "mirror", "blend", "glass"}));
    ASSERT_EQ(s.triangles.size(), 4u);
    EXPECT_EQ(s.triangles[0].material, 2);
    EXPECT_EQ(s.triangles[3].material, 5);
    expectNear(s.camera.position, {0, 1, -10}, "camera");
    EXPECT_NEAR(s.camera.yaw, 0.f, 1e-6f);
    EXPECT_NEAR(s.camera.pitch, 0.f, 1e-6f);
    EXPECT_NEAR(s.camera.fovY, 0.5f, 1e-6f);
    ASSERT_EQ(s.lights.size(), 2u);
    expectNear(s.lights[0].position, {0, 10, 0}, "the file's light");
    ASSERT_EQ(s.planes.size(), 1u);
    EXPECT_EQ(s.planes[0].material, 1);
    EXPECT_NEAR(s.planes[0].offset, 0.f, 1e-2f) << "just below the lowest point, y = 0";
    EXPECT_TRUE(s.hasTransparency());
}

TEST(ModelLoader, PlyQuadWithVertexColours) {
    const Model m = loadModel(kModels / "quad.ply");
    ASSERT_EQ(m.positions.size(), 2u * 3u) << "one quad, two triangles";
    ASSERT_EQ(m.materials.size(), 1u);
    EXPECT_EQ(m.materialNames[0], "default #FF0000");
    expectNear(m.materials[0].diffuse, {1, 0, 0}, "the vertices' red");
    expectNear(m.materials[0].specular, {0.2f, 0.2f, 0.2f}, "the default material's specular");
    for (const glm::vec3& n : m.normals) expectNear(n, {0, 0, 1}, "quad normal");
    EXPECT_FALSE(m.camera.has_value());
    EXPECT_TRUE(m.lights.empty());
    const Scene s = loadScene(kModels / "quad.ply");
    ASSERT_EQ(s.lights.size(), 1u) << "the default light";
    EXPECT_EQ(s.camera.yaw, 0.f) << "the default camera on -z";
    EXPECT_LT(s.camera.position.z, 0.f);
}

// A JSON scene places glTF and PLY models as it does OBJ ones: its material, its transform.
TEST(ModelLoader, JsonSceneMeshesMayBeGltfOrPly) {
    const fs::path dir = rt::test::scratchPath("json_models/");
    const fs::path json = dir / "scene.json";
    std::ofstream(json) << R"({"camera": {"position": [0, 1, -5]},
        "materials": {"m": {"diffuse": [0.1, 0.2, 0.3]}},
        "meshes": [{"file": ")"
                        << fs::absolute(kModels / "quad.ply").string() << R"(",
                    "material": "m", "transform": {"translate": [10, 0, 0]}},
                   {"file": ")"
                        << fs::absolute(kModels / "scene.glb").string() << R"(",
                    "material": "m"}]})";
    const Scene s = loadScene(json);
    ASSERT_EQ(s.triangles.size(), 2u + 4u);
    ASSERT_EQ(s.meshes.size(), 2u);
    expectNear(s.triangles[0].v0, {10, 0, 0}, "the quad moved by the scene's transform");
    expectNear(s.triangles[2].v1, {4, 0, 0}, "the glb's node transform applied");
    for (const dev::Triangle& t : s.triangles) EXPECT_EQ(t.material, 0) << "the scene's material";
    EXPECT_EQ(s.lights.size(), 0u) << "a model's lights stay out of a JSON scene";
}

struct BadModel {
    const char* file;
    const char* message;  // after "tests/data/bad_models/<file>: "
};

const BadModel kBadModels[] = {
    {"truncated.glb", "GLTF: Could not read the file contents"},
    {"broken_json.gltf", "GLTF: JSON parse error, offset 201: Invalid value."},
    {"bad_header.ply", "Invalid .ply file: Unable to extract mesh data"},
    {"points.ply", "no triangles (assimp: Validation failed: Mesh contains no faces)"},
    {"truncated.ply", "mesh 0: face 0 has no vertices (is the file truncated?)"},
    {"index_out_of_range.ply", "Validation failed: aiMesh::mFaces[0]::mIndices[2] is out of range"},
    {"missing_buffer.gltf", "GLTF: could not open referenced file \"nothere.bin\""},
    {"buffer_is_a_device.gltf",
     "GLTF: could not open referenced file \"../../../../../../../../../dev/zero\""},
    {"not_gltf.glb", "not a binary glTF file (it does not start with 'glTF')"},
    {"not_json.gltf", "not a glTF JSON file (it does not start with '{')"},
    {"not_ply.ply", "not a PLY file (it does not start with 'ply')"},
    {"empty.ply", "not a PLY file (it does not start with 'ply')"},
    // Inputs found by fuzzing on which Debian 12's assimp 5.2.5 itself crashes or never returns;
    // the reader process takes the blow (core/model_loader.cpp).
    {"assimp_segfault.glb", "assimp crashed reading the file (Segmentation fault)"},
    {"assimp_endless.ply",
     "assimp did not finish reading the file in 2 s (the reader was stopped)"},
};

// The reader's time limit is cut to 2 s for these files, and restored after.
class BadModelTest : public ::testing::TestWithParam<BadModel> {
  protected:
    void SetUp() override { setModelReadTimeLimit(std::chrono::seconds(2)); }
    void TearDown() override { setModelReadTimeLimit(std::chrono::seconds(120)); }
};

TEST_P(BadModelTest, FailsWithExactOneLineMessage) {
    const std::string path = std::string("tests/data/bad_models/") + GetParam().file;
    const std::string message = loadError(path);
    EXPECT_EQ(message, path + ": " + GetParam().message);
    EXPECT_EQ(message.find('\n'), std::string::npos);
}

INSTANTIATE_TEST_SUITE_P(AllFiles, BadModelTest, ::testing::ValuesIn(kBadModels),
                         [](const auto& info) {
                             std::string name = info.param.file;
                             for (char& c : name)
                                 if (c == '.') c = '_';
                             return name;
                         });

TEST(ModelLoader, EveryBadModelFileIsInTheTable) {
    int files = 0;
    for (const auto& entry : fs::directory_iterator("tests/data/bad_models")) {
        ++files;
        bool listed = false;
        for (const BadModel& b : kBadModels) listed |= entry.path().filename() == b.file;
        EXPECT_TRUE(listed) << entry.path() << " has no expected message";
    }
    EXPECT_EQ(files, int(std::size(kBadModels)));
}

// A buffer or a model that is a FIFO would block the reader forever: refused without opening.
TEST(ModelLoader, FifoIsRefusedNotRead) {
    const fs::path dir = rt::test::scratchPath("fifo/");
    const fs::path fifo = dir / "buffer.bin";
    ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0) << fifo << ": " << std::strerror(errno);
    std::ifstream in(kModels / "scene.gltf");
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string data = "data:application/octet-stream;base64,";
    const std::size_t at = text.find(data);
    ASSERT_NE(at, std::string::npos);
    text.replace(at, text.find('"', at) - at, "buffer.bin");
    std::ofstream(dir / "fifo.gltf") << text;
    const auto start = std::chrono::steady_clock::now();
    EXPECT_EQ(
        loadError(dir / "fifo.gltf"),
        (dir / "fifo.gltf").string() + ": GLTF: could not open referenced file \"buffer.bin\"");
    const fs::path model = dir / "model.ply";
    ASSERT_EQ(mkfifo(model.c_str(), 0600), 0);
    EXPECT_EQ(loadError(model), model.string() + ": cannot open: not a regular file");
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
}

TEST(ModelLoader, BareModelErrorsAreOneLineFromLoadScene) {
    for (const char* file : {"points.ply", "truncated.glb", "broken_json.gltf"}) {
        const fs::path path = fs::path("tests/data/bad_models") / file;
        try {
            loadScene(path);
            ADD_FAILURE() << path << " loaded";
        } catch (const Error& e) {
            const std::string msg = e.what();
            EXPECT_EQ(msg.rfind(path.string() + ": ", 0), 0u) << msg;
            EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
        }
    }
}

// Known values of Debian's assimp-testmodels (scripts/setup installs it).
TEST(ModelLoader, AssimpCorpusValues) {
    RTLAB_REQUIRE_FILE(kCorpus / "PLY");
    EXPECT_EQ(loadModel(kCorpus / "PLY/cube.ply").positions.size() / 3, 12u);
    EXPECT_EQ(loadModel(kCorpus / "PLY/cube_binary.ply").positions.size() / 3, 12u);
    EXPECT_EQ(loadModel(kCorpus / "PLY/Wuson.ply").positions.size() / 3, 3732u)
        << "as many as the OBJ copy, OBJ/WusonOBJ.obj";
    const Bounds cube = bounds(loadModel(kCorpus / "PLY/cube.ply"));
    expectNear(cube.lo, {0, 0, 0}, "cube.ply lo");
    expectNear(cube.hi, {1, 1, 1}, "cube.ply hi");

    // A unit square in z = 0 whose node turns it 45 degrees about -x, and a camera at (0.5,
    // 0.5, 3) with yfov 0.7.
    const Model cameras = loadModel(kCorpus / "glTF2/cameras/Cameras.gltf");
    EXPECT_EQ(cameras.positions.size() / 3, 2u);
    const Bounds square = bounds(cameras);
    expectNear(square.lo, {0, 0, -0.7076f}, "rotated square lo", 1e-3f);
    expectNear(square.hi, {1, 0.7066f, 0}, "rotated square hi", 1e-3f);
    ASSERT_TRUE(cameras.camera.has_value());
    expectNear(cameras.camera->position, {0.5f, 0.5f, 3}, "camera");
    expectNear(cameras.camera->direction, {0, 0, -1}, "camera looks down -z");
    EXPECT_NEAR(cameras.camera->fovY, 0.7f, 1e-6f);
    EXPECT_EQ(cameras.notes.size(), 0u) << "the orthographic camera comes second, unread";

    const Model box = loadModel(kCorpus / "glTF2/BoxBadNormals-glTF-Binary/BoxBadNormals.glb");
    EXPECT_EQ(box.positions.size() / 3, 12u);
    ASSERT_EQ(box.materialNames, std::vector<std::string>{"Red"});
    expectNear(box.materials[0].diffuse, {0.8f, 0, 0}, "Red's base colour");
    for (const glm::vec3& n : box.normals)
        ASSERT_NEAR(glm::length(n), 1.f, 1e-5f) << "bad file normals replaced";

    const Model textured = loadModel(kCorpus / "glTF2/BoxTextured-glTF-Binary/BoxTextured.glb");
    ASSERT_EQ(textured.notes.size(), 1u);
    EXPECT_NE(textured.notes[0].find("textures are not supported"), std::string::npos);

    EXPECT_EQ(loadError(kCorpus / "PLY/points.ply"),
              (kCorpus / "PLY/points.ply").string() +
                  ": no triangles (assimp: Validation failed: Mesh contains no faces)");
    EXPECT_EQ(loadError(kCorpus / "glTF2/BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb"),
              (kCorpus / "glTF2/BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb").string() +
                  ": mesh 'Mesh': non-finite vertex coordinate");
}

}  // namespace
}  // namespace rt
