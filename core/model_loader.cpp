// rtlab — glTF 2.0 and PLY models through assimp (core/model_loader.h).
//
// assimp runs in a child process, the reader. Fuzzing Debian's assimp 5.2.5 found malformed
// .glb and PLY files on which it crashes (segmentation faults in its importers, aborts from its
// assertions, which Debian builds in) or loops forever; in a child, such a file costs the
// child, and the parent reports one line and carries on. The reader copies what this file uses
// of assimp's scene into plain records (RawScene), sends them through a pipe and exits; it is
// killed when it takes longer than the read time limit.
//
// In the reader, assimp parses, validates its own output (ValidateDataStructure), triangulates
// polygons and drops points and lines (SortByPType). Files reach assimp only after a look at
// their first bytes, so that a file named .ply is read by the PLY importer and not by whichever
// of assimp's forty importers claims its content, and every file assimp opens (the model, a
// glTF's .bin buffers) must be a regular file of bounded size, so that a buffer named /dev/zero
// or a FIFO cannot block it. The parent checks the records again (vertex indices, finite
// coordinates, the triangle count), places the meshes in world space and computes normals where
// the file's are missing or unusable.
#include "core/model_loader.h"

#include <assimp/BaseImporter.h>
#include <assimp/DefaultIOSystem.h>
#include <assimp/GltfMaterial.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <new>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <system_error>
#include <tuple>
#include <type_traits>
#include <utility>

#include "core/error.h"

namespace rt {
namespace {

namespace fs = std::filesystem;

constexpr long long kMaxTriangles = 50'000'000;  // same cap as the scene loader
constexpr std::uintmax_t kMaxFileBytes = std::uintmax_t(1) << 30;
constexpr std::size_t kMaxNodes = 1'000'000;  // nodes in the hierarchy
constexpr int kColourLevels = 32;             // vertex colours are quantised to 1/31 steps

std::atomic<long long> readLimitMs{120'000};

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

// ---- What the loader uses of assimp's scene, as plain records ----

struct RawMaterial {
    std::string name;  // empty when the file names none
    bool textured = false, unlit = false;
    std::optional<glm::vec4> baseColor, diffuse, specular, emissive;
    std::optional<float> metallic, roughness, glossiness, opacity, transmission, ior, alphaCutoff;
    std::optional<std::string> alphaMode;
};

struct RawMesh {
    std::string name;
    std::uint32_t material = 0;
    std::vector<glm::vec3> vertices, normals;  // normals: none, or one per vertex
    std::vector<glm::vec4> colours;            // COLOR_0: none, or one per vertex
    std::vector<std::uint32_t> triangles;      // three vertex indices per triangle
};

struct RawNode {
    std::string name;
    std::int32_t parent = -1;  // an earlier node (depth-first order), or -1 for the root
    glm::dmat4 transform{1.0};
    std::vector<std::uint32_t> meshes;
};

struct RawCamera {
    std::string name;
    glm::vec3 lookAt{0.f, 0.f, -1.f};
    float horizontalFov = 0.f, aspect = 0.f, orthographicWidth = 0.f;
};

struct RawLight {
    std::string name;
    std::int32_t type = 0;  // aiLightSourceType
    glm::vec3 position{0.f}, colour{0.f};
};

struct RawScene {
    std::vector<RawMesh> meshes;
    std::vector<RawNode> nodes;
    std::vector<RawMaterial> materials;
    std::vector<RawCamera> cameras;
    std::vector<RawLight> lights;
};

// The pipe's format: each record's fields in order; sizes as 64-bit counts, numbers in host byte
// order (the reader is a fork of this process).
class Writer {
  public:
    template <typename T>
    void put(const T& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        out_.append(reinterpret_cast<const char*>(&v), sizeof v);
    }
    void put(const std::string& s) {
        put(std::uint64_t(s.size()));
        out_.append(s);
    }
    template <typename T>
    void put(const std::optional<T>& v) {
        put(std::uint8_t(v.has_value()));
        if (v) put(*v);
    }
    template <typename T>
    void put(const std::vector<T>& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        put(std::uint64_t(v.size()));
        out_.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
    }
    std::string& bytes() { return out_; }

  private:
    std::string out_;
};

class Reader {
  public:
    explicit Reader(std::string_view in) : in_(in) {}
    template <typename T>
    void get(T& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        take(&v, sizeof v);
    }
    void get(std::string& s) {
        s.resize(count(1));
        take(s.data(), s.size());
    }
    template <typename T>
    void get(std::optional<T>& v) {
        std::uint8_t has = 0;
        get(has);
        v.reset();
        if (has) get(v.emplace());
    }
    template <typename T>
    void get(std::vector<T>& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        v.resize(count(sizeof(T)));
        take(v.data(), v.size() * sizeof(T));
    }
    // A count of elements of `bytes` each (at least 1), no more than the bytes left can hold.
    std::size_t count(std::size_t bytes) {
        std::uint64_t n = 0;
        take(&n, sizeof n);
        if (n > in_.size() / std::max<std::size_t>(bytes, 1)) throw std::length_error("records");
        return std::size_t(n);
    }
    bool done() const { return in_.empty(); }

  private:
    void take(void* to, std::size_t n) {
        if (n > in_.size()) throw std::length_error("records");
        if (n > 0) std::memcpy(to, in_.data(), n);
        in_.remove_prefix(n);
    }
    std::string_view in_;
};

// Each record's fields, once, for both directions.
template <typename IO, typename M>
void fields(const IO& io, M& m) {
    if constexpr (std::is_same_v<std::remove_const_t<M>, RawMaterial>) {
        io(m.name), io(m.textured), io(m.unlit), io(m.baseColor), io(m.diffuse), io(m.specular);
        io(m.emissive), io(m.metallic), io(m.roughness), io(m.glossiness), io(m.opacity);
        io(m.transmission), io(m.ior), io(m.alphaCutoff), io(m.alphaMode);
    } else if constexpr (std::is_same_v<std::remove_const_t<M>, RawMesh>) {
        io(m.name), io(m.material), io(m.vertices), io(m.normals), io(m.colours);
        io(m.triangles);
    } else if constexpr (std::is_same_v<std::remove_const_t<M>, RawNode>) {
        io(m.name), io(m.parent), io(m.transform), io(m.meshes);
    } else if constexpr (std::is_same_v<std::remove_const_t<M>, RawCamera>) {
        io(m.name), io(m.lookAt), io(m.horizontalFov), io(m.aspect), io(m.orthographicWidth);
    } else {
        static_assert(std::is_same_v<std::remove_const_t<M>, RawLight>);
        io(m.name), io(m.type), io(m.position), io(m.colour);
    }
}

template <typename T>
void putRecords(Writer& w, const std::vector<T>& records) {
    w.put(std::uint64_t(records.size()));
    for (const T& r : records) fields([&](const auto& f) { w.put(f); }, r);
}

template <typename T>
void getRecords(Reader& r, std::vector<T>& records) {
    records.resize(r.count(sizeof(std::uint64_t)));
    for (T& rec : records) fields([&](auto& f) { r.get(f); }, rec);
}

std::string serialize(const RawScene& s) {
    Writer w;
    w.put(std::uint8_t('S'));
    putRecords(w, s.meshes);
    putRecords(w, s.nodes);
    putRecords(w, s.materials);
    putRecords(w, s.cameras);
    putRecords(w, s.lights);
    return std::move(w.bytes());
}

RawScene deserialize(std::string_view bytes) {
    Reader r(bytes);
    std::uint8_t tag = 0;
    r.get(tag);
    if (tag != 'S') throw std::length_error("records");
    RawScene s;
    getRecords(r, s.meshes);
    getRecords(r, s.nodes);
    getRecords(r, s.materials);
    getRecords(r, s.cameras);
    getRecords(r, s.lights);
    if (!r.done()) throw std::length_error("records");
    return s;
}

// ---- The reader: assimp's scene into records ----

glm::dmat4 toGlm(const aiMatrix4x4& m) {  // assimp is row-major, glm column-major
    return glm::dmat4(m.a1, m.b1, m.c1, m.d1, m.a2, m.b2, m.c2, m.d2, m.a3, m.b3, m.c3, m.d3, m.a4,
                      m.b4, m.c4, m.d4);
}

std::string text(const aiString& s) { return std::string(s.C_Str(), s.length); }

std::optional<float> getFloat(const aiMaterial& m, const char* key, unsigned type, unsigned index) {
    float v;
    if (m.Get(key, type, index, v) != AI_SUCCESS) return std::nullopt;
    return v;
}

std::optional<glm::vec4> getColour(const aiMaterial& m, const char* key, unsigned type,
                                   unsigned index) {
    aiColor4D c;
    if (m.Get(key, type, index, c) != AI_SUCCESS) return std::nullopt;
    return glm::vec4(c.r, c.g, c.b, c.a);
}

RawMaterial rawMaterial(const aiMaterial& m) {
    RawMaterial out;
    aiString s;
    if (m.Get(AI_MATKEY_NAME, s) == AI_SUCCESS) out.name = text(s);
    for (int t = aiTextureType_DIFFUSE; t <= AI_TEXTURE_TYPE_MAX; ++t)
        out.textured |= m.GetTextureCount(aiTextureType(t)) > 0;
    int shading;
    out.unlit =
        m.Get(AI_MATKEY_SHADING_MODEL, shading) == AI_SUCCESS && shading == aiShadingMode_Unlit;
    out.baseColor = getColour(m, AI_MATKEY_BASE_COLOR);
    out.diffuse = getColour(m, AI_MATKEY_COLOR_DIFFUSE);
    out.specular = getColour(m, AI_MATKEY_COLOR_SPECULAR);
    out.emissive = getColour(m, AI_MATKEY_COLOR_EMISSIVE);
    out.metallic = getFloat(m, AI_MATKEY_METALLIC_FACTOR);
    out.roughness = getFloat(m, AI_MATKEY_ROUGHNESS_FACTOR);
    out.glossiness = getFloat(m, AI_MATKEY_GLOSSINESS_FACTOR);
    out.opacity = getFloat(m, AI_MATKEY_OPACITY);
    out.transmission = getFloat(m, AI_MATKEY_TRANSMISSION_FACTOR);
    out.ior = getFloat(m, AI_MATKEY_REFRACTI);
    out.alphaCutoff = getFloat(m, AI_MATKEY_GLTF_ALPHACUTOFF);
    if (m.Get(AI_MATKEY_GLTF_ALPHAMODE, s) == AI_SUCCESS) out.alphaMode = text(s);
    return out;
}

RawScene rawScene(const fs::path& path, const aiScene& s) {
    RawScene out;
    for (unsigned i = 0; i < s.mNumMeshes; ++i) {
        const aiMesh* m = s.mMeshes[i];
        RawMesh& mesh = out.meshes.emplace_back();
        if (!m) continue;
        mesh.name = text(m->mName);
        mesh.material = m->mMaterialIndex;
        const unsigned nv = m->mNumVertices;
        for (unsigned v = 0; m->mVertices && v < nv; ++v)
            mesh.vertices.emplace_back(m->mVertices[v].x, m->mVertices[v].y, m->mVertices[v].z);
        for (unsigned v = 0; m->mNormals && v < nv; ++v)
            mesh.normals.emplace_back(m->mNormals[v].x, m->mNormals[v].y, m->mNormals[v].z);
        for (unsigned v = 0; m->mColors[0] && v < nv; ++v) {
            const aiColor4D& c = m->mColors[0][v];
            mesh.colours.emplace_back(c.r, c.g, c.b, c.a);
        }
        for (unsigned f = 0; f < m->mNumFaces; ++f) {
            const aiFace& face = m->mFaces[f];
            if (face.mNumIndices == 3 && face.mIndices)
                mesh.triangles.insert(mesh.triangles.end(), face.mIndices, face.mIndices + 3);
        }
    }
    // The hierarchy depth-first, each node after its parent.
    std::vector<std::pair<const aiNode*, std::int32_t>> stack;
    if (s.mRootNode) stack.push_back({s.mRootNode, -1});
    while (!stack.empty()) {
        auto [node, parent] = stack.back();
        stack.pop_back();
        if (out.nodes.size() >= kMaxNodes)
            fail(path, "more than " + std::to_string(kMaxNodes) + " nodes in the hierarchy");
        RawNode& raw = out.nodes.emplace_back();
        raw.name = text(node->mName);
        raw.parent = parent;
        raw.transform = toGlm(node->mTransformation);
        if (node->mMeshes) raw.meshes.assign(node->mMeshes, node->mMeshes + node->mNumMeshes);
        const std::int32_t self = std::int32_t(out.nodes.size() - 1);
        for (unsigned c = node->mNumChildren; c-- > 0;)  // last first: the first pops first
            if (node->mChildren && node->mChildren[c]) stack.push_back({node->mChildren[c], self});
    }
    for (unsigned i = 0; i < s.mNumMaterials; ++i)
        out.materials.push_back(s.mMaterials[i] ? rawMaterial(*s.mMaterials[i]) : RawMaterial{});
    for (unsigned i = 0; i < s.mNumCameras; ++i) {
        const aiCamera* c = s.mCameras[i];
        if (!c) continue;
        out.cameras.push_back({text(c->mName),
                               {c->mLookAt.x, c->mLookAt.y, c->mLookAt.z},
                               c->mHorizontalFOV,
                               c->mAspect,
                               c->mOrthographicWidth});
    }
    for (unsigned i = 0; i < s.mNumLights; ++i) {
        const aiLight* l = s.mLights[i];
        if (!l) continue;
        out.lights.push_back({text(l->mName),
                              std::int32_t(l->mType),
                              {l->mPosition.x, l->mPosition.y, l->mPosition.z},
                              {l->mColorDiffuse.r, l->mColorDiffuse.g, l->mColorDiffuse.b}});
    }
    return out;
}

std::string meshName(const std::string& name, std::size_t index) {
    return name.empty() ? "mesh " + std::to_string(index) : "mesh '" + oneLine(name) + "'";
}

// Checks the faces before assimp's Triangulate step sees them, and sets each mesh's primitive
// types from them. Debian's assimp is built with its assertions on, and that step asserts on a
// face without vertices (a truncated PLY file leaves every face so, and assimp's validation lets
// them through) or on a mesh that claims polygons it does not have.
void prepareFaces(const fs::path& path, const aiScene& scene) {
    for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
        aiMesh* mesh = scene.mMeshes[m];
        if (!mesh) continue;
        unsigned types = 0;
        for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
            const unsigned n = mesh->mFaces[f].mNumIndices;
            if (n == 0 || !mesh->mFaces[f].mIndices)
                fail(path, meshName(text(mesh->mName), m) + ": face " + std::to_string(f) +
                               " has no vertices (is the file truncated?)");
            types |= n == 1   ? aiPrimitiveType_POINT
                     : n == 2 ? aiPrimitiveType_LINE
                     : n == 3 ? aiPrimitiveType_TRIANGLE
                              : aiPrimitiveType_POLYGON;
        }
        mesh->mPrimitiveTypes = types;
    }
}

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

// assimp's reasons for "the file has no faces", which rtlab words as for OBJ.
bool noFaces(const std::string& reason) {
    return reason.find("No meshes remaining") != std::string::npos ||
           reason.find("contains no faces") != std::string::npos ||
           reason.find("has no faces") != std::string::npos;
}

// What the reader sends: the records, or 'E' and the one-line error.
std::string readWithAssimp(const fs::path& path, bool ply) {
    try {
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
                if (std::string why = importerReason(importer, path, ply); !why.empty())
                    reason = why;
            if (noFaces(reason)) fail(path, "no triangles (assimp: " + reason + ")");
            fail(path, reason.empty() ? "assimp cannot read the file" : reason);
        }
        return serialize(rawScene(path, *scene));
    } catch (const Error& e) {
        return "E" + std::string(e.what());
    } catch (const std::bad_alloc&) {
        return "E" + path.string() + ": out of memory";
    } catch (const std::length_error&) {
        return "E" + path.string() + ": out of memory";
    } catch (const std::exception& e) {
        return "E" + path.string() + ": assimp: " + oneLine(e.what());
    } catch (...) {
        return "E" + path.string() + ": assimp failed";
    }
}

bool writeAll(int fd, const std::string& bytes) {
    std::size_t done = 0;
    while (done < bytes.size()) {
        const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return false;
        done += std::size_t(n);
    }
    return true;
}

// Kills and reaps the reader if the parent leaves early (a time limit, an exception).
class Child {
  public:
    explicit Child(pid_t pid) : pid_(pid) {}
    ~Child() {
        if (pid_ > 0) {
            ::kill(pid_, SIGKILL);
            wait();
        }
    }
    Child(const Child&) = delete;
    Child& operator=(const Child&) = delete;

    int wait() {  // the wait status
        int status = 0;
        while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
        }
        pid_ = -1;
        return status;
    }
    void kill() { ::kill(pid_, SIGKILL); }

  private:
    pid_t pid_;
};

// Runs readWithAssimp in a child process and returns what it sent.
std::string readInChild(const fs::path& path, bool ply) {
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0)
        fail(path, std::string("cannot start the assimp reader: ") + std::strerror(errno));
    const pid_t pid = ::fork();
    if (pid < 0) {
        const int err = errno;
        ::close(fds[0]);
        ::close(fds[1]);
        fail(path, std::string("cannot start the assimp reader: ") + std::strerror(err));
    }
    if (pid == 0) {
        // The reader. What assimp prints (an assertion's message) stays out of rtlab's one line;
        // a crash is the default action, reported by the parent, and not a sanitizer's report
        // of code it does not instrument. _exit: no atexit handlers, no stdio of the parent.
        ::close(fds[0]);
        const int null = ::open("/dev/null", O_WRONLY);
        if (null >= 0) {
            ::dup2(null, STDOUT_FILENO);
            ::dup2(null, STDERR_FILENO);
        }
        for (int sig : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) ::signal(sig, SIG_DFL);
        ::_exit(writeAll(fds[1], readWithAssimp(path, ply)) ? 0 : 1);
    }
    ::close(fds[1]);
    Child child(pid);
    std::string bytes;
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::milliseconds(readLimitMs.load());
    char buffer[1 << 16];
    bool timedOut = false;
    for (;;) {
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
            deadline - std::chrono::steady_clock::now());
        if (left.count() <= 0) {
            timedOut = true;
            break;
        }
        pollfd p{fds[0], POLLIN, 0};
        const int ready = ::poll(&p, 1, int(std::min<long long>(left.count(), 1 << 30)));
        if (ready < 0 && errno == EINTR) continue;
        if (ready <= 0) continue;  // the deadline is checked above
        const ssize_t n = ::read(fds[0], buffer, sizeof buffer);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) break;  // end of the records (or a read error: the status tells)
        bytes.append(buffer, std::size_t(n));
    }
    ::close(fds[0]);
    if (timedOut) {
        child.kill();
        child.wait();
        const long long s = readLimitMs.load() / 1000;
        fail(path, "assimp did not finish reading the file in " + std::to_string(s) +
                       " s (the reader was stopped)");
    }
    const int status = child.wait();
    if (WIFSIGNALED(status))
        fail(path,
             std::string("assimp crashed reading the file (") + strsignal(WTERMSIG(status)) + ")");
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || bytes.empty())
        fail(path, "the assimp reader failed (exit status " +
                       std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + ")");
    return bytes;
}

// ---- The parent: records into a Model ----

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

bool finiteMatrix(const glm::dmat4& m) {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            if (!std::isfinite(m[c][r])) return false;
    return true;
}

glm::vec3 clamp01(const glm::vec4& c, glm::vec3 fallback) {
    const glm::dvec3 v(c.r, c.g, c.b);
    return finite(v) ? glm::vec3(glm::clamp(v, 0.0, 1.0)) : fallback;
}

float unit(float v, float fallback) {
    return std::isfinite(v) ? std::clamp(v, 0.f, 1.f) : fallback;
}

float factor(const std::optional<float>& v, float fallback, float lo = 0.f, float hi = 1.f) {
    return v && std::isfinite(*v) ? std::clamp(*v, lo, hi) : fallback;
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
// Blinn-Phong one; scenes/README.md, "glTF 2.0 and PLY models", has the table. `tint` is the
// triangle's mean vertex colour (COLOR_0), which multiplies the base colour.
dev::Material fromPbr(const RawMaterial& m, const glm::vec3& tint) {
    const glm::vec4 c = m.baseColor.value_or(m.diffuse.value_or(glm::vec4(1.f)));
    const glm::vec3 base = clamp01(c, glm::vec3(1.f)) * tint;
    float alpha = unit(c.a, 1.f);
    float metallic = factor(m.metallic, 0.f);
    float roughness = factor(m.roughness, 1.f);
    glm::vec3 diffuse, specular;
    if (m.glossiness) {
        // KHR_materials_pbrSpecularGlossiness: assimp puts its diffuse and specular factors in
        // the diffuse and specular colours.
        const glm::vec4 d = m.diffuse.value_or(glm::vec4(1.f));
        roughness = 1.f - factor(m.glossiness, 1.f);
        metallic = 0.f;
        diffuse = clamp01(d, glm::vec3(1.f)) * tint;
        specular = clamp01(m.specular.value_or(glm::vec4(1.f)), glm::vec3(1.f)) * (1.f - roughness);
        alpha = unit(d.a, 1.f);
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
    out.ambient =
        f3(clamp01(m.emissive.value_or(glm::vec4(0.f)), glm::vec3(0.f)) + 0.05f * diffuse);

    float opacity = 1.f;
    if (m.alphaMode) {
        const float cutoff = factor(m.alphaCutoff, 0.5f);
        opacity = *m.alphaMode == "BLEND"  ? alpha
                  : *m.alphaMode == "MASK" ? (alpha >= cutoff ? 1.f : 0.f)
                                           : 1.f;
    } else {
        opacity = factor(m.opacity, 1.f);
    }
    const float transmission = factor(m.transmission, 0.f);
    out.opacity = opacity * (1.f - transmission);
    // Transmission is glass (glTF's default index 1.5); blending only lets the background through.
    out.ior = transmission > 0.f ? factor(m.ior, 1.5f, 1.f, 4.f) : 1.f;

    if (m.unlit) {
        out.ambient = f3(base);  // KHR_materials_unlit: the base colour, unshaded
        out.diffuse = out.specular = {0.f, 0.f, 0.f};
        out.reflectance = 0.f;
    }
    return out;
}

// A mesh placed by a node: its index and the node's world transform.
struct Instance {
    std::uint32_t mesh;
    glm::dmat4 world;
};

class Builder {
  public:
    Builder(const fs::path& path, const RawScene& s, bool ply) : path_(path), s_(s), ply_(ply) {}

    Model build() {
        worldTransforms();
        std::vector<Instance> placed;
        long long total = 0;
        for (std::size_t n = 0; n < s_.nodes.size(); ++n)
            for (std::uint32_t mesh : s_.nodes[n].meshes) {
                if (mesh >= s_.meshes.size())
                    fail(path_, "node '" + oneLine(s_.nodes[n].name) + "' names mesh " +
                                    std::to_string(mesh) + " of " +
                                    std::to_string(s_.meshes.size()));
                placed.push_back({mesh, world_[n]});
                total += (long long)(s_.meshes[mesh].triangles.size() / 3);
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
    void worldTransforms() {
        world_.resize(s_.nodes.size());
        for (std::size_t n = 0; n < s_.nodes.size(); ++n) {
            const std::int32_t parent = s_.nodes[n].parent;
            if (parent >= std::int32_t(n)) fail(path_, "malformed node hierarchy");
            world_[n] = parent < 0 ? s_.nodes[n].transform : world_[parent] * s_.nodes[n].transform;
        }
    }

    // The first node of that name in depth-first order (as aiNode::FindNode), or -1.
    std::ptrdiff_t findNode(const std::string& name) const {
        for (std::size_t n = 0; n < s_.nodes.size(); ++n)
            if (s_.nodes[n].name == name) return std::ptrdiff_t(n);
        return -1;
    }

    void addInstance(const Instance& inst) {
        const RawMesh& mesh = s_.meshes[inst.mesh];
        const std::string name = meshName(mesh.name, inst.mesh);
        if (!finiteMatrix(inst.world)) fail(path_, name + ": non-finite node transform");
        const glm::dmat3 normalXf = glm::transpose(glm::inverse(glm::dmat3(inst.world)));
        const std::size_t nv = mesh.vertices.size();
        const bool normals = mesh.normals.size() == nv;
        const bool colours = !mesh.colours.empty() && mesh.colours.size() == nv;

        // World positions; the file's vertices must be finite, and stay so when placed.
        std::vector<glm::dvec3> world(nv);
        for (std::size_t i = 0; i < nv; ++i) {
            const glm::dvec3 p(mesh.vertices[i]);
            if (!finite(p)) fail(path_, name + ": non-finite vertex coordinate");
            world[i] = glm::dvec3(inst.world * glm::dvec4(p, 1.0));
            if (!finite(world[i]) || !std::isfinite(float(world[i].x)) ||
                !std::isfinite(float(world[i].y)) || !std::isfinite(float(world[i].z)))
                fail(path_, name + ": vertex coordinates overflow after the node transform");
        }

        // Area-weighted vertex normals, for vertices whose file normal is missing or unusable.
        const std::vector<std::uint32_t>& tri = mesh.triangles;
        std::vector<glm::dvec3> smooth(nv, glm::dvec3(0.0));
        for (std::size_t t = 0; t + 2 < tri.size(); t += 3) {
            for (int k = 0; k < 3; ++k)
                if (tri[t + k] >= nv)
                    fail(path_, name + ": vertex index " + std::to_string(tri[t + k]) +
                                    " out of range (" + std::to_string(nv) + " vertices)");
            const glm::dvec3& a = world[tri[t]];
            const glm::dvec3 n = glm::cross(world[tri[t + 1]] - a, world[tri[t + 2]] - a);
            if (finite(n))
                for (int k = 0; k < 3; ++k) smooth[tri[t + k]] += n;
        }

        for (std::size_t t = 0; t + 2 < tri.size(); t += 3) {
            const std::uint32_t* idx = &tri[t];
            const glm::dvec3 cross =
                glm::cross(world[idx[1]] - world[idx[0]], world[idx[2]] - world[idx[0]]);
            glm::vec3 faceNormal;
            // Zero area (or an overflowing cross product): never hit, dropped as for OBJ.
            if (!unitLength(cross, &faceNormal)) continue;
            for (int k = 0; k < 3; ++k) {
                const std::uint32_t i = idx[k];
                model_.positions.push_back(glm::vec3(world[i]));
                glm::vec3 n;
                bool ok = normals && unitLength(normalXf * glm::dvec3(mesh.normals[i]), &n);
                if (!ok) ok = unitLength(smooth[i], &n);
                model_.normals.push_back(ok ? n : faceNormal);
            }
            glm::vec3 tint(1.f);
            if (colours) {
                glm::dvec3 sum(0.0);
                for (int k = 0; k < 3; ++k) sum += glm::dvec3(glm::vec3(mesh.colours[idx[k]]));
                tint = finite(sum) ? glm::vec3(glm::clamp(sum / 3.0, 0.0, 1.0)) : glm::vec3(1.f);
            }
            model_.triangleMaterial.push_back(material(mesh.material, colours, tint));
        }
    }

    // The rtlab material of the file's material `index` with vertex colour `tint` (quantised):
    // made on first use, so that unused materials do not count toward the scene's limit.
    int material(std::uint32_t index, bool coloured, glm::vec3 tint) {
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
        const RawMaterial* source = index < s_.materials.size() ? &s_.materials[index] : nullptr;
        if (ply_ || !source) {
            // PLY: vertex colours over rtlab's default material, else the default itself.
            m = defaultModelMaterial();
            if (coloured) m.diffuse = f3(tint);
            name = "default";
        } else {
            m = fromPbr(*source, tint);
            name =
                source->name.empty() ? "material " + std::to_string(index) : oneLine(source->name);
            if (source->textured && texturedSeen_.insert(index).second) ++textured_;
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
        for (const RawCamera& cam : s_.cameras) {
            const std::string name = "camera '" + oneLine(cam.name) + "'";
            if (cam.orthographicWidth > 0.f || !(cam.horizontalFov > 0.f)) {
                model_.notes.push_back(path_.string() + ": " + name +
                                       " is orthographic; rtlab renders perspective only");
                continue;
            }
            const std::ptrdiff_t node = findNode(cam.name);
            if (node < 0) continue;  // defined but placed by no node
            const glm::dmat4& world = world_[node];
            const glm::dvec3 position(world * glm::dvec4(0.0, 0.0, 0.0, 1.0));
            const glm::dvec3 look(cam.lookAt);
            glm::vec3 direction;
            // assimp's glTF importer stores yfov * aspectRatio (yfov alone without an aspect
            // ratio) as mHorizontalFOV.
            const double fovY =
                cam.aspect > 0.f ? double(cam.horizontalFov) / cam.aspect : cam.horizontalFov;
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
        for (const RawLight& light : s_.lights) {
            if (light.type != aiLightSource_POINT && light.type != aiLightSource_SPOT) {
                ++directional;
                continue;
            }
            const std::ptrdiff_t node = findNode(light.name);
            if (node < 0) continue;
            const glm::dmat4& world = world_[node];
            const glm::dvec3 local(light.position);
            const glm::dvec3 p(world * glm::dvec4(local, 1.0));
            const glm::dvec3 colour(light.colour);
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
    const RawScene& s_;
    std::vector<glm::dmat4> world_;  // per node
    bool ply_;
    Model model_;
    std::map<std::tuple<unsigned, int, int, int>, int> materials_;
    std::set<unsigned> texturedSeen_;
    int textured_ = 0;
};

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

void setModelReadTimeLimit(std::chrono::milliseconds limit) {
    readLimitMs.store(std::max<long long>(limit.count(), 1));
}

Model loadModel(const std::filesystem::path& path) {
    try {
        if (std::string why = refusal(path); !why.empty()) fail(path, "cannot open: " + why);
        const std::string ext = lowerExtension(path);
        checkSignature(path, ext);
        const std::string bytes = readInChild(path, ext == ".ply");
        if (bytes[0] == 'E') throw Error(bytes.substr(1));
        RawScene raw;
        try {
            raw = deserialize(bytes);
        } catch (const std::length_error&) {
            fail(path, "the assimp reader sent malformed records");
        }
        return Builder(path, raw, ext == ".ply").build();
    } catch (const Error&) {
        throw;
    } catch (const std::bad_alloc&) {
        fail(path, "out of memory");
    } catch (const std::length_error&) {
        fail(path, "out of memory");
    } catch (const std::exception& e) {
        fail(path, oneLine(e.what()));
    }
}

}  // namespace rt
