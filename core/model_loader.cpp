// rtlab — glTF 2.0 and PLY models through assimp (core/model_loader.h).
//
// assimp parses, triangulates polygons, drops points and lines (SortByPType) and validates its
// own output (ValidateDataStructure) before this file reads it. What assimp lets through is
// checked again here: vertex indices, finite coordinates, the triangle count, and normals (the
// file's where they are usable, else area-weighted ones). Files reach assimp only after a look
// at their first bytes, so that a file named .ply is read by the PLY importer and not by
// whichever of assimp's forty importers claims its content, and every file assimp opens (the
// model, a glTF's .bin buffers) must be a regular file of bounded size, so that a buffer named
// /dev/zero or a FIFO cannot hang the loader.
#include "core/model_loader.h"

#include <assimp/BaseImporter.h>
#include <assimp/DefaultIOSystem.h>
#include <assimp/GltfMaterial.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <new>
#include <set>
#include <string>
#include <string_view>
#include <system_error>
#include <tuple>
#include <utility>

#include "core/error.h"

namespace rt {
namespace {

namespace fs = std::filesystem;

constexpr long long kMaxTriangles = 50'000'000;  // same cap as the scene loader
constexpr std::uintmax_t kMaxFileBytes = std::uintmax_t(1) << 30;
constexpr std::size_t kMaxNodes = 1'000'000;  // nodes visited in the hierarchy
constexpr int kColourLevels = 32;             // vertex colours are quantised to 1/31 steps

[[noreturn]] void fail(const fs::path& path, const std::string& reason) {
    throw Error(path.string() + ": " + reason);
}

// assimp's messages on one printable line: control characters and runs of spaces become one
// space, and the text is cut at 300 characters.
std::string oneLine(const std::string& s) {
    std::string out;
    for (char c : s) {
        const bool space = c == ' ' || (static_cast<unsigned char>(c) < 32);
        if (space) {
            if (!out.empty() && out.back() != ' ') out += ' ';
        } else {
            out += static_cast<unsigned char>(c) < 127 ? c : '?';
        }
    }
    while (!out.empty() && out.back() == ' ') out.pop_back();
    if (out.size() > 300) out = out.substr(0, 297) + "...";
    return out;
}

std::string lowerExtension(const fs::path& path) {
    std::string ext = path.extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

// Why `file` may not be opened (empty: it may): only regular files of at most kMaxFileBytes.
std::string refusal(const fs::path& file) {
    std::error_code ec;
    const fs::file_status st = fs::status(file, ec);
    if (ec || !fs::exists(st)) return "No such file or directory";
    if (fs::is_directory(st)) return "Is a directory";
    if (!fs::is_regular_file(st)) return "not a regular file";
    const std::uintmax_t size = fs::file_size(file, ec);
    if (ec) return ec.message();
    if (size > kMaxFileBytes)
        return "file too large (more than " + std::to_string(kMaxFileBytes >> 30) + " GiB)";
    return "";
}

// assimp's own file access, limited to regular files of bounded size (a refused file reads as
// missing, and the importer reports it by name).
class BoundedIOSystem : public Assimp::DefaultIOSystem {
  public:
    bool Exists(const char* file) const override {
        return refusal(file).empty() && DefaultIOSystem::Exists(file);
    }
    Assimp::IOStream* Open(const char* file, const char* mode) override {
        if (std::strchr(mode, 'w') || std::strchr(mode, 'a') || !refusal(file).empty())
            return nullptr;
        return DefaultIOSystem::Open(file, mode);
    }
};

// The file's first bytes must match its extension (PLY "ply", GLB "glTF", glTF JSON '{').
void checkSignature(const fs::path& path, const std::string& ext) {
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) fail(path, std::string("cannot open: ") + std::strerror(errno));
    char head[64] = {};
    const std::size_t n = std::fread(head, 1, sizeof head, f);
    std::fclose(f);
    const std::string_view h(head, n);
    if (ext == ".ply") {
        if (h.substr(0, 3) != "ply") fail(path, "not a PLY file (it does not start with 'ply')");
    } else if (ext == ".glb") {
        if (h.substr(0, 4) != "glTF")
            fail(path, "not a binary glTF file (it does not start with 'glTF')");
    } else {
        std::size_t i = h.substr(0, 3) == "\xEF\xBB\xBF" ? 3 : 0;  // UTF-8 byte order mark
        while (i < h.size() && std::isspace(static_cast<unsigned char>(h[i]))) ++i;
        if (i >= h.size() || h[i] != '{')
            fail(path, "not a glTF JSON file (it does not start with '{')");
    }
}

bool finite(const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// Normalizes in double so that tiny (denormal) vectors still give unit ones.
bool unitLength(const glm::dvec3& v, glm::vec3* out) {
    const double len = glm::length(v);
    if (!(len > 0.0) || !std::isfinite(len)) return false;
    *out = glm::vec3(v / len);
    return std::isfinite(out->x + out->y + out->z);
}

glm::dmat4 toGlm(const aiMatrix4x4& m) {  // assimp is row-major, glm column-major
    return glm::dmat4(m.a1, m.b1, m.c1, m.d1, m.a2, m.b2, m.c2, m.d2, m.a3, m.b3, m.c3, m.d3, m.a4,
                      m.b4, m.c4, m.d4);
}

glm::dmat4 worldTransform(const aiNode* node) {
    glm::dmat4 m(1.0);
    for (std::size_t depth = 0; node && depth < kMaxNodes; node = node->mParent, ++depth)
        m = toGlm(node->mTransformation) * m;
    return m;
}

bool finiteMatrix(const glm::dmat4& m) {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            if (!std::isfinite(m[c][r])) return false;
    return true;
}

glm::vec3 clamp01(const aiColor4D& c, glm::vec3 fallback) {
    const glm::dvec3 v(c.r, c.g, c.b);
    return finite(v) ? glm::vec3(glm::clamp(v, 0.0, 1.0)) : fallback;
}

float factor(const aiMaterial& m, const char* key, unsigned type, unsigned index, float fallback,
             float lo = 0.f, float hi = 1.f) {
    float v;
    if (m.Get(key, type, index, v) != AI_SUCCESS || !std::isfinite(v)) return fallback;
    return std::clamp(v, lo, hi);
}

dev::Float3 f3(const glm::vec3& v) { return {v.x, v.y, v.z}; }

dev::Material blank() {  // the JSON format's defaults for the keys models do not set
    dev::Material m{};
    m.exponent = 1.f;
    m.opacity = m.ior = 1.f;
    m.pattern = RT_PATTERN_NONE;
    m.octaves = 4;
    m.patternScale = 1.f;
    m.diffuse2 = {0.1f, 0.1f, 0.1f};
    m.bump = 0.5f;
    return m;
}

// glTF's metallic-roughness material (and its specular-glossiness extension) as rtlab's
// Blinn-Phong one; scenes/README.md, "glTF and PLY models", has the table. `tint` is the
// triangle's mean vertex colour (COLOR_0), which multiplies the base colour.
dev::Material fromPbr(const aiMaterial& m, const glm::vec3& tint) {
    aiColor4D c(1.f, 1.f, 1.f, 1.f);
    if (m.Get(AI_MATKEY_BASE_COLOR, c) != AI_SUCCESS) m.Get(AI_MATKEY_COLOR_DIFFUSE, c);
    glm::vec3 base = clamp01(c, glm::vec3(1.f)) * tint;
    float alpha = std::isfinite(c.a) ? std::clamp(c.a, 0.f, 1.f) : 1.f;
    float metallic = factor(m, AI_MATKEY_METALLIC_FACTOR, 0.f);
    float roughness = factor(m, AI_MATKEY_ROUGHNESS_FACTOR, 1.f);
    glm::vec3 diffuse, specular;
    float glossiness;
    if (m.Get(AI_MATKEY_GLOSSINESS_FACTOR, glossiness) == AI_SUCCESS) {
        // KHR_materials_pbrSpecularGlossiness: assimp puts its diffuse and specular factors in
        // the diffuse and specular colours.
        aiColor4D d(1.f, 1.f, 1.f, 1.f), s(1.f, 1.f, 1.f, 1.f);
        m.Get(AI_MATKEY_COLOR_DIFFUSE, d);
        m.Get(AI_MATKEY_COLOR_SPECULAR, s);
        roughness = 1.f - (std::isfinite(glossiness) ? std::clamp(glossiness, 0.f, 1.f) : 1.f);
        metallic = 0.f;
        diffuse = clamp01(d, glm::vec3(1.f)) * tint;
        specular = clamp01(s, glm::vec3(1.f)) * (1.f - roughness);
        alpha = std::isfinite(d.a) ? std::clamp(d.a, 0.f, 1.f) : 1.f;
    } else {
        // A rough metal scatters its colour broadly: it keeps that much of it as diffuse.
        diffuse = base * (1.f - metallic * (1.f - roughness));
        specular = glm::mix(glm::vec3(0.04f), base, metallic) * (1.f - roughness);
    }
    dev::Material out = blank();
    out.diffuse = f3(diffuse);
    out.specular = f3(specular);
    const double r4 = std::pow(double(roughness), 4.0);  // alpha^2, alpha = roughness^2
    out.exponent = r4 > 0.0 ? float(std::clamp(2.0 / r4 - 2.0, 1.0, 10000.0)) : 10000.f;
    out.reflectance = metallic * (1.f - roughness);
    aiColor4D e(0.f, 0.f, 0.f, 0.f);
    m.Get(AI_MATKEY_COLOR_EMISSIVE, e);
    out.ambient = f3(clamp01(e, glm::vec3(0.f)) + 0.05f * diffuse);

    aiString mode;
    float opacity = 1.f;
    if (m.Get(AI_MATKEY_GLTF_ALPHAMODE, mode) == AI_SUCCESS) {
        const std::string s = mode.C_Str();
        const float cutoff = factor(m, AI_MATKEY_GLTF_ALPHACUTOFF, 0.5f);
        opacity = s == "BLEND" ? alpha : s == "MASK" ? (alpha >= cutoff ? 1.f : 0.f) : 1.f;
    } else {
        opacity = factor(m, AI_MATKEY_OPACITY, 1.f);
    }
    const float transmission = factor(m, AI_MATKEY_TRANSMISSION_FACTOR, 0.f);
    out.opacity = opacity * (1.f - transmission);
    // Transmission is glass (glTF's default index 1.5); blending only lets the background through.
    out.ior = transmission > 0.f ? factor(m, AI_MATKEY_REFRACTI, 1.5f, 1.f, 4.f) : 1.f;

    int shading;
    if (m.Get(AI_MATKEY_SHADING_MODEL, shading) == AI_SUCCESS && shading == aiShadingMode_Unlit) {
        out.ambient = f3(base);  // KHR_materials_unlit: the base colour, unshaded
        out.diffuse = out.specular = {0.f, 0.f, 0.f};
        out.reflectance = 0.f;
    }
    return out;
}

bool hasTextures(const aiMaterial& m) {
    for (int t = aiTextureType_DIFFUSE; t <= AI_TEXTURE_TYPE_MAX; ++t)
        if (m.GetTextureCount(aiTextureType(t)) > 0) return true;
    return false;
}

std::string materialName(const aiScene& s, unsigned index) {
    aiString name;
    if (index < s.mNumMaterials && s.mMaterials[index]->Get(AI_MATKEY_NAME, name) == AI_SUCCESS &&
        name.length > 0)
        return oneLine(name.C_Str());
    return "material " + std::to_string(index);
}

std::string meshName(const aiMesh& mesh, unsigned index) {
    return mesh.mName.length > 0 ? "mesh '" + oneLine(mesh.mName.C_Str()) + "'"
                                 : "mesh " + std::to_string(index);
}

// A mesh placed by a node: its index and the node's world transform.
struct Instance {
    unsigned mesh;
    glm::dmat4 world;
};

std::vector<Instance> instances(const fs::path& path, const aiScene& s) {
    std::vector<Instance> out;
    if (!s.mRootNode) return out;
    std::vector<std::pair<const aiNode*, glm::dmat4>> stack = {
        {s.mRootNode, toGlm(s.mRootNode->mTransformation)}};
    std::size_t visited = 0;
    while (!stack.empty()) {
        auto [node, world] = stack.back();
        stack.pop_back();
        if (++visited > kMaxNodes)
            fail(path, "more than " + std::to_string(kMaxNodes) + " nodes in the hierarchy");
        for (unsigned i = 0; i < node->mNumMeshes; ++i) {
            if (node->mMeshes[i] >= s.mNumMeshes)
                fail(path, "node '" + oneLine(node->mName.C_Str()) + "' names mesh " +
                               std::to_string(node->mMeshes[i]) + " of " +
                               std::to_string(s.mNumMeshes));
            out.push_back({node->mMeshes[i], world});
        }
        // Children pushed last to first, so that meshes come out in the file's node order.
        for (unsigned i = node->mNumChildren; i-- > 0;)
            if (const aiNode* child = node->mChildren[i])
                stack.push_back({child, world * toGlm(child->mTransformation)});
    }
    return out;
}

class Builder {
  public:
    Builder(const fs::path& path, const aiScene& s, bool ply) : path_(path), s_(s), ply_(ply) {}

    Model build() {
        const std::vector<Instance> placed = instances(path_, s_);
        long long total = 0;
        for (const Instance& inst : placed) {
            const aiMesh* mesh = s_.mMeshes[inst.mesh];
            for (unsigned f = 0; mesh && f < mesh->mNumFaces; ++f)
                total += mesh->mFaces[f].mNumIndices == 3;
        }
        if (total == 0) fail(path_, "no triangles");
        if (total > kMaxTriangles)
            fail(path_, "too many triangles: " + std::to_string(total) + " (at most " +
                            std::to_string(kMaxTriangles) + ")");
        for (const Instance& inst : placed) addInstance(inst);
        if (model_.positions.empty())
            fail(path_, "all " + std::to_string(total) + " triangles are degenerate (zero area)");
        if (textured_ > 0)
            model_.notes.push_back(
                path_.string() + ": textures are not supported; " + std::to_string(textured_) +
                (textured_ == 1 ? " material renders with its" : " materials render with their") +
                " colour factors only");
        camera();
        lights();
        return std::move(model_);
    }

  private:
    void addInstance(const Instance& inst) {
        const aiMesh& mesh = *s_.mMeshes[inst.mesh];
        if (!finiteMatrix(inst.world))
            fail(path_, meshName(mesh, inst.mesh) + ": non-finite node transform");
        const glm::dmat3 normalXf = glm::transpose(glm::inverse(glm::dmat3(inst.world)));
        const unsigned nv = mesh.mNumVertices;
        if (nv > 0 && !mesh.mVertices) fail(path_, meshName(mesh, inst.mesh) + ": no positions");

        // World positions; the file's vertices must be finite, and stay so when placed.
        std::vector<glm::dvec3> world(nv);
        for (unsigned i = 0; i < nv; ++i) {
            const aiVector3D& v = mesh.mVertices[i];
            const glm::dvec3 p(v.x, v.y, v.z);
            if (!finite(p))
                fail(path_, meshName(mesh, inst.mesh) + ": non-finite vertex coordinate");
            world[i] = glm::dvec3(inst.world * glm::dvec4(p, 1.0));
            if (!finite(world[i]) || !std::isfinite(float(world[i].x)) ||
                !std::isfinite(float(world[i].y)) || !std::isfinite(float(world[i].z)))
                fail(path_, meshName(mesh, inst.mesh) +
                                ": vertex coordinates overflow after the node transform");
        }

        // Area-weighted vertex normals, for vertices whose file normal is missing or unusable.
        std::vector<glm::dvec3> smooth(nv, glm::dvec3(0.0));
        for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
            const aiFace& face = mesh.mFaces[f];
            if (face.mNumIndices != 3 || !face.mIndices) continue;
            for (int k = 0; k < 3; ++k)
                if (face.mIndices[k] >= nv)
                    fail(path_, meshName(mesh, inst.mesh) + ": vertex index " +
                                    std::to_string(face.mIndices[k]) + " out of range (" +
                                    std::to_string(nv) + " vertices)");
            const glm::dvec3& a = world[face.mIndices[0]];
            const glm::dvec3 n =
                glm::cross(world[face.mIndices[1]] - a, world[face.mIndices[2]] - a);
            if (finite(n))
                for (int k = 0; k < 3; ++k) smooth[face.mIndices[k]] += n;
        }

        const bool colours = mesh.HasVertexColors(0);
        for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
            const aiFace& face = mesh.mFaces[f];
            if (face.mNumIndices != 3 || !face.mIndices) continue;
            const unsigned* idx = face.mIndices;
            const glm::dvec3 cross =
                glm::cross(world[idx[1]] - world[idx[0]], world[idx[2]] - world[idx[0]]);
            glm::vec3 faceNormal;
            // Zero area (or an overflowing cross product): never hit, dropped as for OBJ.
            if (!unitLength(cross, &faceNormal)) continue;
            for (int k = 0; k < 3; ++k) {
                const unsigned i = idx[k];
                model_.positions.push_back(glm::vec3(world[i]));
                glm::vec3 n;
                bool ok = false;
                if (mesh.mNormals) {
                    const aiVector3D& fn = mesh.mNormals[i];
                    ok = unitLength(normalXf * glm::dvec3(fn.x, fn.y, fn.z), &n);
                }
                if (!ok) ok = unitLength(smooth[i], &n);
                model_.normals.push_back(ok ? n : faceNormal);
            }
            glm::vec3 tint(1.f);
            if (colours) {
                glm::dvec3 sum(0.0);
                for (int k = 0; k < 3; ++k) {
                    const aiColor4D& c = mesh.mColors[0][idx[k]];
                    sum += glm::dvec3(c.r, c.g, c.b);
                }
                tint = finite(sum) ? glm::vec3(glm::clamp(sum / 3.0, 0.0, 1.0)) : glm::vec3(1.f);
            }
            model_.triangleMaterial.push_back(material(mesh.mMaterialIndex, colours, tint));
        }
    }

    // The rtlab material of the file's material `index` with vertex colour `tint` (quantised):
    // made on first use, so that unused materials do not count toward the scene's limit.
    int material(unsigned index, bool coloured, glm::vec3 tint) {
        int q[3] = {-1, -1, -1};
        if (coloured)
            for (int k = 0; k < 3; ++k) {
                q[k] = int(std::lround(tint[k] * (kColourLevels - 1)));
                tint[k] = float(q[k]) / float(kColourLevels - 1);
            }
        const auto key = std::make_tuple(index, q[0], q[1], q[2]);
        if (auto it = materials_.find(key); it != materials_.end()) return it->second;

        dev::Material m;
        std::string name;
        const aiMaterial* source = index < s_.mNumMaterials ? s_.mMaterials[index] : nullptr;
        if (ply_ || !source) {
            // PLY: vertex colours over rtlab's default material, else the default itself.
            m = defaultModelMaterial();
            if (coloured) m.diffuse = f3(tint);
            name = "default";
        } else {
            m = fromPbr(*source, tint);
            name = materialName(s_, index);
            if (hasTextures(*source) && texturedSeen_.insert(index).second) ++textured_;
        }
        if (coloured) {
            char hex[16];
            std::snprintf(hex, sizeof hex, " #%02X%02X%02X", unsigned(std::lround(tint.r * 255)),
                          unsigned(std::lround(tint.g * 255)), unsigned(std::lround(tint.b * 255)));
            name += hex;
        }
        const int id = int(model_.materials.size());
        model_.materials.push_back(m);
        model_.materialNames.push_back(name);
        materials_.emplace(key, id);
        return id;
    }

    // The first perspective camera placed by a node: glTF cameras sit at their node's origin
    // and look down its -z axis (assimp's mLookAt). assimp 5.2 also copies the node's
    // translation into aiCamera::mPosition, which would count it twice, so that is not read.
    void camera() {
        for (unsigned c = 0; c < s_.mNumCameras; ++c) {
            const aiCamera* cam = s_.mCameras[c];
            if (!cam) continue;
            const std::string name = "camera '" + oneLine(cam->mName.C_Str()) + "'";
            if (cam->mOrthographicWidth > 0.f || !(cam->mHorizontalFOV > 0.f)) {
                model_.notes.push_back(path_.string() + ": " + name +
                                       " is orthographic; rtlab renders perspective only");
                continue;
            }
            const aiNode* node = s_.mRootNode ? s_.mRootNode->FindNode(cam->mName) : nullptr;
            if (!node) continue;  // defined but placed by no node
            const glm::dmat4 world = worldTransform(node);
            const glm::dvec3 position(world * glm::dvec4(0.0, 0.0, 0.0, 1.0));
            const glm::dvec3 look(cam->mLookAt.x, cam->mLookAt.y, cam->mLookAt.z);
            glm::vec3 direction;
            // assimp's glTF importer stores yfov * aspectRatio (yfov alone without an aspect
            // ratio) as mHorizontalFOV.
            const double fovY = cam->mAspect > 0.f ? double(cam->mHorizontalFOV) / cam->mAspect
                                                   : cam->mHorizontalFOV;
            if (!finiteMatrix(world) || !finite(position) ||
                !unitLength(glm::dmat3(world) * look, &direction) || !(fovY > 0.0) ||
                !(fovY < 3.14159265358979)) {
                model_.notes.push_back(path_.string() + ": " + name +
                                       " has an unusable placement or field of view; ignored");
                continue;
            }
            model_.camera = ModelCamera{glm::vec3(position), direction, float(fovY)};
            return;
        }
    }

    // Point and spot lights (a spot's cone is ignored). rtlab's lights do not fall off with
    // distance, so the file's intensities become relative: every colour is divided by the
    // largest channel of any of them.
    void lights() {
        std::vector<dev::Light> found;
        int directional = 0, extra = 0;
        for (unsigned l = 0; l < s_.mNumLights; ++l) {
            const aiLight* light = s_.mLights[l];
            if (!light) continue;
            if (light->mType != aiLightSource_POINT && light->mType != aiLightSource_SPOT) {
                ++directional;
                continue;
            }
            const aiNode* node = s_.mRootNode ? s_.mRootNode->FindNode(light->mName) : nullptr;
            if (!node) continue;
            const glm::dmat4 world = worldTransform(node);
            const glm::dvec3 local(light->mPosition.x, light->mPosition.y, light->mPosition.z);
            const glm::dvec3 p(world * glm::dvec4(local, 1.0));
            const glm::dvec3 colour(light->mColorDiffuse.r, light->mColorDiffuse.g,
                                    light->mColorDiffuse.b);
            if (!finiteMatrix(world) || !finite(p) || !finite(colour) ||
                !std::isfinite(float(p.x + p.y + p.z)))
                continue;
            if (found.size() == RT_MAX_LIGHTS) {
                ++extra;
                continue;
            }
            dev::Light out{};
            out.position = f3(glm::vec3(p));
            out.color = f3(glm::vec3(glm::max(colour, 0.0)));
            found.push_back(out);
        }
        float peak = 0.f;
        for (const dev::Light& l : found) peak = std::max({peak, l.color.x, l.color.y, l.color.z});
        for (dev::Light& l : found) {
            if (peak > 0.f && std::isfinite(peak)) {
                l.color = {l.color.x / peak, l.color.y / peak, l.color.z / peak};
            } else {
                l.color = {1.f, 1.f, 1.f};
            }
        }
        model_.lights = std::move(found);
        if (directional > 0)
            model_.notes.push_back(path_.string() + ": " + std::to_string(directional) +
                                   " directional or area light(s) ignored; rtlab has point lights");
        if (extra > 0)
            model_.notes.push_back(path_.string() + ": " + std::to_string(extra) +
                                   " light(s) beyond the first " + std::to_string(RT_MAX_LIGHTS) +
                                   " ignored");
    }

    const fs::path& path_;
    const aiScene& s_;
    bool ply_;
    Model model_;
    std::map<std::tuple<unsigned, int, int, int>, int> materials_;
    std::set<unsigned> texturedSeen_;
    int textured_ = 0;
};

// Why the format's own importer rejects the file. assimp's Importer asks each importer whether
// it can read a file, and a glTF importer that cannot parse it just says no, so the Importer's
// message is "No suitable reader found"; the glTF 2 (or PLY) importer run by itself says what
// is wrong.
std::string importerReason(Assimp::Importer& importer, const fs::path& path, bool ply) {
    const char* wanted = ply ? "Stanford Polygon Library (PLY) Importer" : "glTF2 Importer";
    for (std::size_t i = 0; i < importer.GetImporterCount(); ++i) {
        const aiImporterDesc* desc = importer.GetImporterInfo(i);
        Assimp::BaseImporter* format = importer.GetImporter(i);
        if (!desc || !format || std::strcmp(desc->mName, wanted) != 0) continue;
        delete format->ReadFile(&importer, path.string(), importer.GetIOHandler());
        return oneLine(format->GetErrorText());
    }
    return "";
}

// Checks the faces before assimp's Triangulate step sees them, and sets each mesh's primitive
// types from them. Debian's assimp is built with its assertions on, and that step asserts,
// aborting the process, on a face without vertices (a truncated PLY file leaves every face so,
// and assimp's validation lets them through) or a mesh that claims polygons it does not have.
void prepareFaces(const fs::path& path, const aiScene& scene) {
    for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
        aiMesh* mesh = scene.mMeshes[m];
        if (!mesh) continue;
        unsigned types = 0;
        for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
            const unsigned n = mesh->mFaces[f].mNumIndices;
            if (n == 0 || !mesh->mFaces[f].mIndices)
                fail(path, meshName(*mesh, m) + ": face " + std::to_string(f) +
                               " has no vertices (is the file truncated?)");
            types |= n == 1   ? aiPrimitiveType_POINT
                     : n == 2 ? aiPrimitiveType_LINE
                     : n == 3 ? aiPrimitiveType_TRIANGLE
                              : aiPrimitiveType_POLYGON;
        }
        mesh->mPrimitiveTypes = types;
    }
}

// assimp's reasons for "the file has no faces", which rtlab words as for OBJ.
bool noFaces(const std::string& reason) {
    return reason.find("No meshes remaining") != std::string::npos ||
           reason.find("contains no faces") != std::string::npos ||
           reason.find("has no faces") != std::string::npos;
}

}  // namespace

dev::Material defaultModelMaterial() {
    dev::Material m = blank();
    m.diffuse = {0.7f, 0.7f, 0.7f};
    m.specular = {0.2f, 0.2f, 0.2f};
    m.ambient = {0.05f, 0.05f, 0.05f};
    m.exponent = 32.f;
    return m;
}

bool isModelFile(const std::filesystem::path& path) {
    const std::string ext = lowerExtension(path);
    return ext == ".gltf" || ext == ".glb" || ext == ".ply";
}

Model loadModel(const std::filesystem::path& path) {
    try {
        if (std::string why = refusal(path); !why.empty()) fail(path, "cannot open: " + why);
        const std::string ext = lowerExtension(path);
        checkSignature(path, ext);

        Assimp::Importer importer;
        importer.SetIOHandler(new BoundedIOSystem);  // the importer owns and deletes it
        importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                                    aiPrimitiveType_POINT | aiPrimitiveType_LINE);
        const aiScene* scene = importer.ReadFile(path.string(), aiProcess_ValidateDataStructure);
        if (scene) {
            prepareFaces(path, *scene);
            scene = importer.ApplyPostProcessing(aiProcess_Triangulate | aiProcess_SortByPType);
        }
        if (!scene) {
            std::string reason = oneLine(importer.GetErrorString());
            if (reason.find("No suitable reader found") != std::string::npos)
                if (std::string why = importerReason(importer, path, ext == ".ply"); !why.empty())
                    reason = why;
            if (noFaces(reason)) fail(path, "no triangles (assimp: " + reason + ")");
            fail(path, reason.empty() ? "assimp cannot read the file" : reason);
        }
        return Builder(path, *scene, ext == ".ply").build();
    } catch (const Error&) {
        throw;
    } catch (const std::bad_alloc&) {
        fail(path, "out of memory");
    } catch (const std::length_error&) {
        fail(path, "out of memory");
    } catch (const std::exception& e) {
        fail(path, "assimp: " + oneLine(e.what()));
    }
}

}  // namespace rt
