// rtlab — OBJ meshes for scenes (core/scene_loader.cpp) and bare-OBJ renders.
//
// tinyobjloader does the parsing and the n-gon triangulation, but it silently reads broken data:
// a non-numeric coordinate becomes 0, an index past the start of the file becomes a negative
// array index (its n-gon path then reads out of bounds), an overflowing index wraps. So a strict
// line scanner runs first and rejects such files with the line number; tinyobjloader only ever
// sees text that the scanner accepted, and its indices are checked again afterwards.
#include "core/obj_loader.h"

#include <tiny_obj_loader.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <new>
#include <sstream>
#include <string>
#include <string_view>

#include "core/error.h"

namespace rt {
namespace {

namespace fs = std::filesystem;

constexpr long long kMaxTriangles = 50'000'000;  // same cap as the scene loader
// tinyobjloader's ear clipper is quadratic to cubic in the polygon size; bound it.
constexpr int kMaxFaceVertices = 1024;
constexpr std::size_t kMaxFileBytes = std::size_t(4) << 30;

[[noreturn]] void fail(const fs::path& path, const std::string& reason) {
    throw Error(path.string() + ": " + reason);
}

// Quotes a token for a message: at most 32 characters, non-printable bytes as '?'.
std::string quoted(std::string_view s) {
    std::string out = "'";
    for (std::size_t i = 0; i < s.size() && i < 32; ++i)
        out += (s[i] >= 32 && s[i] < 127) ? s[i] : '?';
    return out + (s.size() > 32 ? "...'" : "'");
}

// Reads the whole file, failing early on binary data (checked per chunk, so that a device such as
// /dev/urandom fails at once instead of filling memory).
std::string readText(const fs::path& path) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) fail(path, "cannot open: Is a directory");
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) fail(path, std::string("cannot open: ") + std::strerror(errno));
    std::string text, problem;
    char buffer[1 << 16];
    std::size_t n;
    while (problem.empty() && (n = std::fread(buffer, 1, sizeof buffer, f)) > 0) {
        if (text.empty() && n >= 2 &&
            ((buffer[0] == '\xFE' && buffer[1] == '\xFF') ||
             (buffer[0] == '\xFF' && buffer[1] == '\xFE')))
            problem = "UTF-16 text is not supported; save the file as UTF-8";
        else if (const void* nul = std::memchr(buffer, 0, n))
            problem = "binary data (NUL byte at offset " +
                      std::to_string(text.size() + (static_cast<const char*>(nul) - buffer)) +
                      "), not a text OBJ file";
        else if (text.size() + n > kMaxFileBytes)
            problem = "file too large (more than " + std::to_string(kMaxFileBytes >> 30) + " GiB)";
        else
            text.append(buffer, n);
    }
    const bool bad = problem.empty() && std::ferror(f);
    const int err = errno;
    std::fclose(f);
    if (!problem.empty()) fail(path, problem);
    if (bad) fail(path, std::string("cannot read: ") + std::strerror(err));
    if (text.compare(0, 3, "\xEF\xBB\xBF") == 0) text.erase(0, 3);  // UTF-8 byte order mark
    return text;
}

std::string counted(long long n, const char* one, const char* many) {
    return std::to_string(n) + " " + (n == 1 ? one : many);
}

bool isSpace(char c) { return c == ' ' || c == '\t'; }

// Splits a line into space/tab separated tokens (tinyobjloader also stops a token at '\r').
std::vector<std::string_view> tokens(std::string_view line) {
    std::vector<std::string_view> out;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (isSpace(line[i]) || line[i] == '\r')) ++i;
        std::size_t j = i;
        while (j < line.size() && !isSpace(line[j]) && line[j] != '\r') ++j;
        if (j > i) out.push_back(line.substr(i, j - i));
        i = j;
    }
    return out;
}

// A decimal number, the whole token: [+-] (digits [. digits] | . digits) [eE [+-] digits].
// Also what tinyobjloader accepts, but it would stop at trailing junk ("3.1+e2" reads 3.1).
bool parseNumber(std::string_view s, double* value) {
    std::size_t i = 0, digits = 0;
    if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
    while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i, ++digits;
    if (i < s.size() && s[i] == '.')
        for (++i; i < s.size() && s[i] >= '0' && s[i] <= '9'; ++i) ++digits;
    if (digits == 0) return false;
    if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
        ++i;
        if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
        std::size_t expDigits = 0;
        while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i, ++expDigits;
        if (expDigits == 0) return false;
    }
    if (i != s.size()) return false;
    *value = std::strtod(std::string(s).c_str(), nullptr);
    return true;
}

enum class LineKind { kOther, kVertex, kTexcoord, kNormal, kFace, kIndices };

// Classifies a line the way tinyobjloader does: keyword, then a space, tab or the line end.
LineKind classify(std::string_view& line) {
    std::size_t i = 0;
    while (i < line.size() && isSpace(line[i])) ++i;
    line.remove_prefix(i);
    auto starts = [&](std::string_view key) {
        return line.substr(0, key.size()) == key &&
               (line.size() == key.size() || isSpace(line[key.size()]));
    };
    if (starts("v")) return LineKind::kVertex;
    if (starts("vt")) return LineKind::kTexcoord;
    if (starts("vn")) return LineKind::kNormal;
    if (starts("f")) return LineKind::kFace;
    if (starts("l") || starts("p")) return LineKind::kIndices;
    return LineKind::kOther;
}

// Calls fn(line, lineNumber) for every line; lines end at "\n", "\r\n" or "\r" as in
// tinyobjloader.
template <typename Fn>
void forEachLine(std::string_view text, Fn&& fn) {
    long long lineNo = 0;
    std::size_t pos = 0;
    while (pos < text.size()) {
        std::size_t end = std::min(text.find_first_of("\r\n", pos), text.size());
        fn(text.substr(pos, end - pos), ++lineNo);
        pos = end + (text.compare(end, 2, "\r\n") == 0 ? 2 : 1);
    }
}

// Pre-pass over the text: numbers, face sizes and every index, with line numbers. Positive
// indices may refer forward (tinyobjloader allows it), so a first pass counts the elements.
class Scanner {
  public:
    explicit Scanner(const fs::path& path) : path_(path) {}

    void scan(std::string_view text) {
        forEachLine(text, [&](std::string_view line, long long) {
            LineKind kind = classify(line);
            if (kind == LineKind::kVertex) ++total_[0];
            if (kind == LineKind::kTexcoord) ++total_[1];
            if (kind == LineKind::kNormal) ++total_[2];
        });
        forEachLine(text, [&](std::string_view line, long long lineNo) { scanLine(line, lineNo); });
    }

    long long faces() const { return faces_; }

  private:
    static constexpr const char* kKindNames[3] = {"vertex", "texcoord", "normal"};
    static constexpr const char* kPlural[3] = {"vertices", "texcoords", "normals"};

    [[noreturn]] void error(long long line, const std::string& reason) const {
        fail(path_, "line " + std::to_string(line) + ": " + reason);
    }

    void scanLine(std::string_view line, long long lineNo) {
        const LineKind kind = classify(line);
        if (kind == LineKind::kOther) return;
        const std::vector<std::string_view> t = tokens(line);
        if (kind == LineKind::kVertex) {
            numbers(t, lineNo, "vertex");
            ++count_[0];
        } else if (kind == LineKind::kTexcoord) {
            ++count_[1];  // texture coordinates are not used; only their count matters
        } else if (kind == LineKind::kNormal) {
            numbers(t, lineNo, "normal");
            ++count_[2];
        } else {
            const bool face = kind == LineKind::kFace;
            const std::size_t n = t.size() - 1;
            if (face && n < 3)
                error(lineNo,
                      "face has " + counted(n, "vertex", "vertices") + ", needs at least 3");
            if (face && n > std::size_t(kMaxFaceVertices))
                error(lineNo, "face has " + std::to_string(n) + " vertices (at most " +
                                  std::to_string(kMaxFaceVertices) + ")");
            for (std::size_t k = 1; k < t.size(); ++k) corner(t[k], lineNo);
            if (face) ++faces_;
        }
    }

    void numbers(const std::vector<std::string_view>& t, long long lineNo, const char* what) {
        if (t.size() < 4)
            error(lineNo,
                  std::string(what) + " needs 3 coordinates, got " + std::to_string(t.size() - 1));
        for (int k = 1; k <= 3; ++k) {
            double v;
            if (!parseNumber(t[k], &v)) error(lineNo, "bad number " + quoted(t[k]));
            if (!std::isfinite(float(v)))
                error(lineNo, "coordinate " + quoted(t[k]) + " is not a finite 32-bit float");
        }
    }

    // One face corner: v, v/t, v//n or v/t/n.
    void corner(std::string_view s, long long lineNo) {
        if (std::count(s.begin(), s.end(), '/') > 2) error(lineNo, "bad face corner " + quoted(s));
        std::size_t slash1 = s.find('/');
        checkIndex(s.substr(0, slash1), 0, lineNo, s);
        if (slash1 == std::string_view::npos) return;
        std::string_view rest = s.substr(slash1 + 1);
        std::size_t slash2 = rest.find('/');
        std::string_view tex = rest.substr(0, slash2);
        if (!tex.empty() || slash2 == std::string_view::npos) checkIndex(tex, 1, lineNo, s);
        if (slash2 != std::string_view::npos) checkIndex(rest.substr(slash2 + 1), 2, lineNo, s);
    }

    void checkIndex(std::string_view s, int kind, long long lineNo, std::string_view corner) {
        long long value = 0;
        const char* end = s.data() + s.size();
        auto [ptr, ec] = std::from_chars(s.data(), end, value);
        if (ec == std::errc::result_out_of_range && ptr == end)
            error(lineNo, std::string(kKindNames[kind]) + " index " + quoted(s) + " out of range");
        if (s.empty() || ec != std::errc() || ptr != end)
            error(lineNo, "bad face corner " + quoted(corner));
        if (value == 0)
            error(lineNo, std::string(kKindNames[kind]) + " index 0 in " + quoted(corner) +
                              " (OBJ indices start at 1)");
        if (value < 0 && -value > count_[kind])
            error(lineNo, std::string(kKindNames[kind]) + " index " + std::to_string(value) +
                              " reaches before the first " + kKindNames[kind] + " (" +
                              std::to_string(count_[kind]) + " defined so far)");
        if (value > total_[kind])
            error(lineNo, std::string(kKindNames[kind]) + " index " + std::to_string(value) +
                              " out of range (" +
                              counted(total_[kind], kKindNames[kind], kPlural[kind]) +
                              " in the file)");
    }

    fs::path path_;
    long long count_[3] = {0, 0, 0};  // v, vt, vn lines so far
    long long total_[3] = {0, 0, 0};  // ... in the whole file
    long long faces_ = 0;
};

glm::vec3 vertexAt(const tinyobj::attrib_t& a, int i) {
    return {a.vertices[3 * i], a.vertices[3 * i + 1], a.vertices[3 * i + 2]};
}

glm::vec3 normalAt(const tinyobj::attrib_t& a, int i) {
    return {a.normals[3 * i], a.normals[3 * i + 1], a.normals[3 * i + 2]};
}

bool finite(const glm::vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// Normalizes in double so that tiny (denormal) cross products still give unit vectors.
bool unitLength(const glm::vec3& v, glm::vec3* out) {
    glm::dvec3 d(v);
    double len = glm::length(d);
    if (!(len > 0.0) || !std::isfinite(len)) return false;
    *out = glm::vec3(d / len);
    return true;
}

// Warnings of tinyobjloader that mean broken geometry (the scanner should have caught them).
glm::vec3 unitColor(const tinyobj::real_t* c) {
    glm::vec3 v(c[0], c[1], c[2]);
    return finite(v) ? glm::clamp(v, 0.f, 1.f) : glm::vec3(0.f);
}

float clampFinite(float v, float lo, float hi, float fallback) {
    return std::isfinite(v) ? std::clamp(v, lo, hi) : fallback;
}

ObjMaterial toMaterial(const tinyobj::material_t& m) {
    ObjMaterial out;
    out.name = m.name;
    out.ambient = unitColor(m.ambient);
    out.diffuse = unitColor(m.diffuse);
    out.specular = unitColor(m.specular);
    out.shininess = clampFinite(m.shininess, 1.f, 10000.f, 1.f);
    out.ior = clampFinite(m.ior, 1.f, 4.f, 1.f);
    out.dissolve = clampFinite(m.dissolve, 0.f, 1.f, 1.f);
    out.illum = m.illum;
    return out;
}

// Reads mtllib files beside the OBJ, but only regular files of a sane size: a library named
// /dev/urandom (or a FIFO) would otherwise be read forever. A refused library is reported like a
// missing one, and the model renders with the default material.
class BoundedMtlReader : public tinyobj::MaterialReader {
  public:
    explicit BoundedMtlReader(fs::path base)
        : base_(std::move(base)), files_(base_.string() + "/") {}
    bool operator()(const std::string& name, std::vector<tinyobj::material_t>* materials,
                    std::map<std::string, int>* names, std::string* warn,
                    std::string* err) override {
        std::error_code ec;
        const fs::path file = base_ / name;
        if (!fs::is_regular_file(file, ec) || fs::file_size(file, ec) > kMaxMtlBytes || ec) {
            if (warn) *warn += "Material file [ " + name + " ] not found or not a readable file\n";
            return false;
        }
        return files_(name, materials, names, warn, err);
    }

  private:
    static constexpr std::uintmax_t kMaxMtlBytes = 64u << 20;
    fs::path base_;
    tinyobj::MaterialFileReader files_;
};

// tinyobjloader reports a missing or unreadable .mtl as a warning; rtlab then renders with its
// default material, and says so.
std::string materialNote(const std::string& warn) {
    std::istringstream lines(warn);
    std::string line;
    while (std::getline(lines, line))
        if (line.find("Material file") != std::string::npos ||
            line.find("material file") != std::string::npos)
            return line;
    return "";
}

void checkWarnings(const fs::path& path, const std::string& warn) {
    std::istringstream lines(warn);
    std::string line;
    while (std::getline(lines, line))
        if (line.find("invalid vertex index") != std::string::npos ||
            line.find("out of bounds") != std::string::npos ||
            line.find("Degenerated face") != std::string::npos)
            fail(path, line);
}

ObjMesh build(const fs::path& path, const tinyobj::attrib_t& attrib,
              const std::vector<tinyobj::shape_t>& shapes,
              const std::vector<tinyobj::material_t>& materials) {
    const int vertexCount = int(attrib.vertices.size() / 3);
    const int normalCount = int(attrib.normals.size() / 3);
    std::vector<tinyobj::index_t> corners;
    std::vector<int> faceMaterial;  // per kept triangle
    bool fileNormals = true;
    long long total = 0;
    for (const tinyobj::shape_t& shape : shapes) {
        const auto& idx = shape.mesh.indices;
        if (idx.size() % 3 != 0) fail(path, "triangulation left a non-triangle face");
        for (std::size_t t = 0; t < idx.size(); t += 3) {
            ++total;
            for (int k = 0; k < 3; ++k) {
                const tinyobj::index_t& c = idx[t + k];
                if (c.vertex_index < 0 || c.vertex_index >= vertexCount)
                    fail(path,
                         "vertex index " + std::to_string(c.vertex_index + 1) + " out of range");
                if (c.normal_index >= normalCount)
                    fail(path,
                         "normal index " + std::to_string(c.normal_index + 1) + " out of range");
                if (!finite(vertexAt(attrib, c.vertex_index)))
                    fail(path, "non-finite vertex coordinate");
                if (c.normal_index < 0) fileNormals = false;
            }
            glm::vec3 v0 = vertexAt(attrib, idx[t].vertex_index);
            glm::vec3 n = glm::cross(vertexAt(attrib, idx[t + 1].vertex_index) - v0,
                                     vertexAt(attrib, idx[t + 2].vertex_index) - v0);
            if (n == glm::vec3(0.f) || !finite(n)) continue;  // zero area: never hit, dropped
            corners.insert(corners.end(), idx.begin() + t, idx.begin() + t + 3);
            const std::size_t f = t / 3;
            const int m = f < shape.mesh.material_ids.size() ? shape.mesh.material_ids[f] : -1;
            faceMaterial.push_back(m >= 0 && m < int(materials.size()) ? m : -1);
        }
    }
    if (total == 0) fail(path, "no triangles");
    if (corners.empty())
        fail(path, "all " + std::to_string(total) + " triangles are degenerate (zero area)");
    if (total > kMaxTriangles)
        fail(path, "too many triangles: " + std::to_string(total) + " (at most " +
                       std::to_string(kMaxTriangles) + ")");

    ObjMesh mesh;
    mesh.triangleMaterial = std::move(faceMaterial);
    for (const tinyobj::material_t& m : materials) mesh.materials.push_back(toMaterial(m));
    mesh.positions.reserve(corners.size());
    for (const tinyobj::index_t& c : corners)
        mesh.positions.push_back(vertexAt(attrib, c.vertex_index));

    // The file's normals, when every corner has a usable one.
    if (fileNormals) {
        for (const tinyobj::index_t& c : corners) {
            glm::vec3 n;
            if (!unitLength(normalAt(attrib, c.normal_index), &n)) {
                fileNormals = false;
                break;
            }
            mesh.normals.push_back(n);
        }
        if (fileNormals) return mesh;
        mesh.normals.clear();
    }

    // Area-weighted smooth normals per position index: |e1 x e2| is twice the area.
    std::vector<glm::vec3> sum(vertexCount, glm::vec3(0.f));
    std::vector<glm::vec3> face(corners.size() / 3);
    for (std::size_t t = 0; t < corners.size(); t += 3) {
        const glm::vec3* p = &mesh.positions[t];
        glm::vec3 n = glm::cross(p[1] - p[0], p[2] - p[0]);
        unitLength(n, &face[t / 3]);
        for (int k = 0; k < 3; ++k) sum[corners[t + k].vertex_index] += n;
    }
    mesh.normals.resize(corners.size());
    for (std::size_t i = 0; i < corners.size(); ++i) {
        // Opposite faces sharing a vertex can cancel; fall back to the face normal.
        if (!unitLength(sum[corners[i].vertex_index], &mesh.normals[i]))
            mesh.normals[i] = face[i / 3];
    }
    return mesh;
}

}  // namespace

ObjMesh loadObj(const std::filesystem::path& path) {
    try {
        std::string text = readText(path);
        Scanner scanner(path);
        scanner.scan(text);
        if (scanner.faces() == 0) fail(path, "no triangles");

        tinyobj::attrib_t attrib;
        std::vector<tinyobj::shape_t> shapes;
        std::vector<tinyobj::material_t> materials;
        std::string warn, err;
        std::istringstream in(std::move(text));
        // mtllib files are looked up beside the OBJ file, as the format says.
        const fs::path base = path.parent_path().empty() ? fs::path(".") : path.parent_path();
        BoundedMtlReader mtl(base);
        bool ok = tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &in, &mtl,
                                   /*triangulate=*/true, /*default_vcols_fallback=*/false);
        if (!ok || !err.empty()) {
            std::string first = err.substr(0, err.find('\n'));
            fail(path, first.empty() ? "cannot parse" : first);
        }
        checkWarnings(path, warn);
        ObjMesh mesh = build(path, attrib, shapes, materials);
        mesh.materialNote = materialNote(warn);
        return mesh;
    } catch (const std::bad_alloc&) {
        fail(path, "out of memory");
    } catch (const std::length_error&) {
        fail(path, "out of memory");
    }
}

}  // namespace rt
