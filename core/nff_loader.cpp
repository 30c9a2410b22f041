// rtlab — the NFF reader (docs/NFF.md): one pass over the file's lines, entity by entity, into
// rt::Scene in NFF's own coordinates; then one improper rotation takes NFF's `up` to rtlab's +y
// and its right-handed view to rtlab's camera (SHADING.md section 1), which has no roll.
#include "core/nff_loader.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <glm/glm.hpp>
#include <map>
#include <string_view>
#include <vector>

#include "core/accel.h"
#include "core/error.h"
#include "core/scene_loader.h"

namespace rt {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kMaxSpheres = 1'000'000;
constexpr std::size_t kMaxTriangles = 50'000'000;
constexpr long kMaxPolygonVertices = 1'000'000;
constexpr double kPi = 3.14159265358979323846;

std::string printable(std::string_view s, std::size_t most = 40) {
    std::string out(s.substr(0, most));
    for (char& c : out)
        if (c < 32 || c > 126) c = '?';
    return s.size() > most ? out + "..." : out;
}

std::string num(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

// A word of the file and the line it is on.
struct Token {
    std::string_view text;
    int line = 0;
};

// The file's words, split at white space; `#` starts a comment to the end of its line. NFF's
// entities are words, not lines (the SPD writes a cone's 8 numbers on its `c` line; NFF.TXT
// puts them on two lines of their own): the reader takes either.
class Tokens {
  public:
    explicit Tokens(const std::string& text) : text_(text) {}

    bool next(Token& t) {
        if (!peek(t)) return false;
        at_ = peekEnd_;
        last_ = t.line;
        return true;
    }
    bool peek(Token& t) {
        std::size_t i = at_;
        int line = line_;
        for (;;) {
            while (i < text_.size() && std::isspace(static_cast<unsigned char>(text_[i])))
                if (text_[i++] == '\n') ++line;
            if (i < text_.size() && text_[i] == '#') {
                while (i < text_.size() && text_[i] != '\n') ++i;
                continue;
            }
            break;
        }
        at_ = i;  // white space and comments need not be skipped again
        line_ = line;
        if (i >= text_.size()) return false;
        std::size_t j = i;
        while (j < text_.size() && !std::isspace(static_cast<unsigned char>(text_[j]))) ++j;
        t = {std::string_view(text_.data() + i, j - i), line};
        peekEnd_ = j;
        return true;
    }
    int last() const { return last_; }  // the line of the last word taken

  private:
    const std::string& text_;
    std::size_t at_ = 0, peekEnd_ = 0;
    int line_ = 1, last_ = 1;
};

struct FillLine {  // an `f` line as written
    double v[8];
    bool operator<(const FillLine& o) const {
        return std::lexicographical_compare(v, v + 8, o.v, o.v + 8);
    }
};

class Parser {
  public:
    Parser(const std::string& text, const fs::path& file, const NffOptions& options)
        : tokens_(text), file_(file), options_(options) {}

    Scene parse() {
        scene_.name = file_.stem().string();
        scene_.source = file_;
        Token t;
        while (tokens_.next(t)) entity(t);
        if (!viewpoint_) fail(tokens_.last(), "no viewpoint ('v') in the file");
        finish();
        return std::move(scene_);
    }

  private:
    [[noreturn]] void fail(int line, const std::string& reason) const {
        throw Error(file_.string() + ": line " + std::to_string(line) + ": " + reason);
    }

    static bool parse(std::string_view text, double& v) {
        const std::string token(text);
        char* end = nullptr;
        v = std::strtod(token.c_str(), &end);
        return end != token.c_str() && *end == '\0';
    }

    // The next word, a finite float: `field` of the entity `what` begun at `start`.
    double number(const Token& start, const std::string& what, const std::string& field) {
        Token t;
        if (!tokens_.next(t))
            fail(start.line, "truncated " + what + ": the file ends before its " + field);
        double v;
        if (!parse(t.text, v)) {
            const std::string where =
                t.line == start.line ? "" : " (of line " + std::to_string(start.line) + ")";
            fail(t.line,
                 what + where + ": expected its " + field + ", got '" + printable(t.text) + "'");
        }
        if (!std::isfinite(v) || !std::isfinite(float(v)))
            fail(t.line,
                 what + ": " + field + " '" + printable(t.text) + "' is not a finite 32-bit float");
        return v;
    }

    glm::dvec3 point(const Token& start, const std::string& what, const std::string& field) {
        const double x = number(start, what, field + " x");
        const double y = number(start, what, field + " y");
        return {x, y, number(start, what, field + " z")};
    }

    void entity(const Token& t) {
        const std::string_view k = t.text;
        if (k == "v") return view(t);
        if (k == "b") {
            const glm::dvec3 c = point(t, "background 'b'", "colour");
            for (int i = 0; i < 3; ++i)
                if (c[i] < 0) fail(t.line, "background colour must be >= 0, got " + num(c[i]));
            background_ = {float(c.x), float(c.y), float(c.z)};
            return;
        }
        if (k == "l") return light(t);
        if (k == "f") return fill(t);
        if (k == "s") return sphere(t);
        if (k == "p" || k == "pp") return polygon(t, k == "pp");
        if (k == "c") return cone(t);
        fail(t.line, "unknown keyword '" + printable(k) +
                         "' (NFF entities are v, b, l, f, s, p, pp, c and # comments)");
    }

    void view(const Token& t) {
        if (viewpoint_) fail(t.line, "a second viewpoint ('v')");
        viewpoint_ = true;
        const char* keys[] = {"from", "at", "up", "angle", "hither", "resolution"};
        double v[6][3] = {};
        int line[6] = {};
        for (int i = 0; i < 6; ++i) {
            Token k;
            if (!tokens_.next(k))
                fail(t.line, std::string("truncated viewpoint: the file ends before its '") +
                                 keys[i] + "'");
            if (k.text != keys[i])
                fail(k.line, "viewpoint: expected '" + std::string(keys[i]) + "', got '" +
                                 printable(k.text) + "'");
            line[i] = k.line;
            const int n = i < 3 ? 3 : i == 5 ? 2 : 1;
            for (int j = 0; j < n; ++j)
                v[i][j] = number(k, std::string("viewpoint '") + keys[i] + "'",
                                 "value " + std::to_string(j + 1));
        }
        from_ = {v[0][0], v[0][1], v[0][2]};
        at_ = {v[1][0], v[1][1], v[1][2]};
        const glm::dvec3 up(v[2][0], v[2][1], v[2][2]);
        if (from_ == at_) fail(line[1], "viewpoint: 'from' and 'at' are the same point");
        if (glm::length(up) == 0.0) fail(line[2], "viewpoint: 'up' is the zero vector");
        up_ = glm::normalize(up);
        if (glm::length(glm::cross(glm::normalize(at_ - from_), up_)) < 1e-9)
            fail(line[2], "viewpoint: 'up' is parallel to the view direction");
        if (!(v[3][0] > 0 && v[3][0] < 180))
            fail(line[3], "viewpoint: 'angle' must be in (0, 180) degrees, got " + num(v[3][0]));
        for (int j = 0; j < 2; ++j)
            if (v[5][j] != std::floor(v[5][j]) || v[5][j] < 1 || v[5][j] > 16384)
                fail(line[5],
                     "viewpoint: 'resolution' must be integers in 1..16384, got " + num(v[5][j]));
        fovY_ = float(v[3][0] * kPi / 180);
        scene_.defaults.width = int(v[5][0]);
        scene_.defaults.height = int(v[5][1]);
    }

    void light(const Token& t) {
        const std::string what = "light 'l'";
        dev::Light light{};
        const glm::dvec3 p = point(t, what, "position");
        light.position = {float(p.x), float(p.y), float(p.z)};
        light.color = {1, 1, 1};
        // The colour is optional: numbers on the `l` line's own line.
        Token next;
        double ignored;
        if (tokens_.peek(next) && next.line == t.line && parse(next.text, ignored)) {
            const glm::dvec3 c = point(t, what, "colour");
            for (int i = 0; i < 3; ++i)
                if (c[i] < 0) fail(t.line, "light colour must be >= 0, got " + num(c[i]));
            light.color = {float(c.x), float(c.y), float(c.z)};
        }
        if (scene_.lights.size() == RT_MAX_LIGHTS)
            fail(t.line, "more than " + std::to_string(RT_MAX_LIGHTS) +
                             " lights (rtlab's limit, RT_MAX_LIGHTS)");
        scene_.lights.push_back(light);
    }

    void fill(const Token& t) {
        const char* names[] = {"red", "green", "blue", "Kd", "Ks", "Shine", "T", "ior"};
        FillLine m;
        for (int i = 0; i < 8; ++i) m.v[i] = number(t, "fill 'f'", names[i]);
        addFill(t.line, m);
    }

    void addFill(int line, const FillLine& m) {
        const double* v = m.v;
        const char* names[] = {"red", "green", "blue", "Kd", "Ks", "Shine", "T", "ior"};
        for (int i = 0; i < 7; ++i)
            if (v[i] < 0) fail(line, std::string(names[i]) + " must be >= 0, got " + num(v[i]));
        if (v[4] > 1) fail(line, "Ks must be in [0, 1], got " + num(v[4]));
        if (v[6] > 1) fail(line, "T must be in [0, 1], got " + num(v[6]));
        if (v[6] > 0 && !(v[7] > 0))
            fail(line, "a transmitting material (T > 0) needs an index of refraction > 0, got " +
                           num(v[7]));
        auto [it, fresh] = materialIndex_.try_emplace(m, int(scene_.materials.size()));
        if (fresh) {
            if (scene_.materials.size() == RT_MAX_MATERIALS)
                fail(line, "more than " + std::to_string(RT_MAX_MATERIALS) + " distinct materials");
            scene_.materials.push_back(toMaterial(m));
            std::string name = "f";  // (not "f" + ...: GCC 12's -Wrestrict false positive)
            name += std::to_string(scene_.materials.size() - 1);
            scene_.materialNames.push_back(name);
        }
        material_ = it->second;
    }

    // docs/NFF.md, "Materials".
    static dev::Material toMaterial(const FillLine& f) {
        const double* v = f.v;
        dev::Material m{};
        m.diffuse = {float(v[3] * v[0]), float(v[3] * v[1]), float(v[3] * v[2])};
        m.specular = {float(v[4]), float(v[4]), float(v[4])};
        m.exponent = float(v[5]);
        m.reflectance = float(v[4]);
        m.opacity = float(1 - v[6]);
        m.ior = v[6] > 0 ? float(v[7]) : 1.f;
        m.diffuse2 = {0.1f, 0.1f, 0.1f};
        m.patternScale = 1.f;
        return m;
    }

    int currentMaterial(int line) {
        if (material_ >= 0) return material_;
        // Objects before any `f`: white and diffuse, as `f 1 1 1 1 0 0 0 1` would make them.
        addFill(line, FillLine{{1, 1, 1, 1, 0, 0, 0, 1}});
        scene_.notes.push_back(file_.string() + ": line " + std::to_string(line) +
                               ": an object before any fill material 'f': white and diffuse");
        return material_;
    }

    void sphere(const Token& t) {
        const std::string what = "sphere 's'";
        const glm::dvec3 c = point(t, what, "centre");
        const double r = number(t, what, "radius");
        if (r == 0) fail(t.line, "sphere of radius 0");
        if (scene_.spheres.size() == kMaxSpheres)
            fail(t.line, "more than " + std::to_string(kMaxSpheres) + " spheres");
        if (r < 0) insideOnly_ = true;
        dev::Sphere s{};
        s.center = {float(c.x), float(c.y), float(c.z)};
        s.radius = float(std::fabs(r));
        s.material = currentMaterial(t.line);
        scene_.spheres.push_back(s);
    }

    void polygon(const Token& t, bool patch) {
        const std::string what = patch ? "polygon patch 'pp'" : "polygon 'p'";
        const double n = number(t, what, "vertex count");
        if (n != std::floor(n) || n < 3)
            fail(t.line, what + " of " + num(n) + " vertices (at least 3)");
        if (n > kMaxPolygonVertices)
            fail(t.line, what + " of " + num(n) + " vertices (at most " +
                             std::to_string(kMaxPolygonVertices) + ")");
        std::vector<glm::dvec3> p, nrm;
        for (long i = 0; i < long(n); ++i) {
            const std::string vertex = "vertex " + std::to_string(i + 1) + " of " + num(n);
            p.push_back(point(t, what, vertex));
            if (patch) {
                const glm::dvec3 nv = point(t, what, vertex + "'s normal");
                if (glm::length(nv) == 0.0)
                    fail(tokens_.last(), what + ": " + vertex + "'s normal is the zero vector");
                nrm.push_back(glm::normalize(nv));
            }
        }
        const int m = currentMaterial(t.line);
        // NFF polygons are convex: a fan from the first vertex. Triangles without area (the
        // teapot's patches meet in points at the lid and the bottom) are left out: no ray hits
        // them.
        for (std::size_t i = 1; i + 1 < p.size(); ++i) {
            glm::dvec3 face = glm::cross(p[i] - p[0], p[i + 1] - p[0]);
            if (!(glm::length(face) > 0)) {
                ++skipped_;
                continue;
            }
            face = glm::normalize(face);
            if (patch)
                addTriangle(t.line, {p[0], p[i], p[i + 1]}, {nrm[0], nrm[i], nrm[i + 1]}, m);
            else
                addTriangle(t.line, {p[0], p[i], p[i + 1]}, {face, face, face}, m);
        }
    }

    void cone(const Token& t) {
        const std::string what = "cone 'c'";
        const glm::dvec3 base = point(t, what, "base");
        const double br = number(t, what, "base radius");
        const glm::dvec3 apex = point(t, what, "apex");
        const double ar = number(t, what, "apex radius");
        const double h = glm::length(apex - base);
        if (h == 0) fail(t.line, "cone whose base and apex are the same point");
        if (br < 0 || ar < 0) insideOnly_ = true;
        const double r0 = std::fabs(br), r1 = std::fabs(ar);
        if (r0 == 0 && r1 == 0) fail(t.line, "cone whose radii are both 0");
        const glm::dvec3 w = (apex - base) / h;
        const glm::dvec3 u = glm::normalize(
            glm::cross(w, std::fabs(w.x) < 0.6 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0)));
        const glm::dvec3 v = glm::cross(w, u);
        const int m = currentMaterial(t.line);
        const int k = options_.coneSegments;
        auto ring = [&](int i) {
            const double a = 2 * kPi * (i % k) / k;
            return std::cos(a) * u + std::sin(a) * v;
        };
        for (int i = 0; i < k; ++i) {
            const glm::dvec3 d0 = ring(i), d1 = ring(i + 1);
            // The side's normal leans toward the narrow end by (r0 - r1) / h.
            const glm::dvec3 n0 = glm::normalize(h * d0 + (r0 - r1) * w);
            const glm::dvec3 n1 = glm::normalize(h * d1 + (r0 - r1) * w);
            const glm::dvec3 b0 = base + r0 * d0, b1 = base + r0 * d1;
            const glm::dvec3 a0 = apex + r1 * d0, a1 = apex + r1 * d1;
            if (r0 > 0) addTriangle(t.line, {b0, b1, a1}, {n0, n1, n1}, m);
            if (r1 > 0) addTriangle(t.line, {b0, a1, a0}, {n0, n1, n0}, m);
        }
    }

    struct Tri {
        glm::dvec3 v[3];
    };
    void addTriangle(int line, Tri p, Tri n, int material) {
        if (scene_.triangles.size() == kMaxTriangles)
            fail(line, "more than " + std::to_string(kMaxTriangles) + " triangles");
        tris_.push_back(p);
        normals_.push_back(n);
        triMaterial_.push_back(material);
    }

    // NFF's right-handed view (screen right = view x up) in rtlab's camera, whose screen right is
    // up x view: an improper rotation M, first the rotation taking `up` to +z, then y <-> z.
    // M takes `up` to +y, so the camera needs no roll; triangles swap two vertices so that their
    // front (counter-clockwise, NFF) stays the side rtlab sees as outside.
    void finish() {
        const glm::dvec3 z(0, 0, 1);
        glm::dmat3 q(1.0);  // glm is column-major: q[c][r]
        const double c = glm::dot(up_, z);
        if (c < -1 + 1e-12) {
            q = glm::dmat3(1, 0, 0, 0, -1, 0, 0, 0, -1);
        } else {
            const glm::dvec3 x = glm::cross(up_, z);
            const glm::dmat3 k(0, x.z, -x.y, -x.z, 0, x.x, x.y, -x.x, 0);
            q = glm::dmat3(1.0) + k + k * k * (1 / (1 + c));
        }
        const glm::dmat3 swap(1, 0, 0, 0, 0, 1, 0, 1, 0);
        const glm::dmat3 mtx = swap * q;
        auto f3 = [&](const glm::dvec3& p) {
            const glm::dvec3 r = mtx * p;
            const dev::Float3 f{float(r.x), float(r.y), float(r.z)};
            if (!std::isfinite(f.x) || !std::isfinite(f.y) || !std::isfinite(f.z))
                throw Error(file_.string() +
                            ": a coordinate near the 32-bit float limit "
                            "overflows once 'up' is turned to rtlab's +y");
            return f;
        };
        auto unit3 = [&](const glm::dvec3& p) { return f3(glm::normalize(p)); };
        for (dev::Sphere& s : scene_.spheres) s.center = f3({s.center.x, s.center.y, s.center.z});
        const float intensity =
            scene_.lights.empty() ? 1.f : float(1 / std::sqrt(scene_.lights.size()));
        for (dev::Light& lt : scene_.lights) {
            lt.position = f3({lt.position.x, lt.position.y, lt.position.z});
            lt.color = {lt.color.x * intensity, lt.color.y * intensity, lt.color.z * intensity};
        }
        scene_.triangles.reserve(tris_.size());
        for (std::size_t t = 0; t < tris_.size(); ++t) {
            const Tri& p = tris_[t];
            const Tri& n = normals_[t];
            scene_.triangles.push_back({f3(p.v[0]), f3(p.v[2]), f3(p.v[1]), unit3(n.v[0]),
                                        unit3(n.v[2]), unit3(n.v[1]), triMaterial_[t], 0});
        }
        if (!scene_.triangles.empty())
            scene_.meshes.push_back({0, int(scene_.triangles.size()), -1, 0, {}, {}, {}, 0.f, {}});
        const glm::dvec3 d = glm::normalize(mtx * (at_ - from_));
        scene_.camera = {f3(from_),
                         float(std::atan2(d.x, d.z)),
                         float(std::asin(std::clamp(d.y, -1.0, 1.0))),
                         fovY_,
                         {0, 0}};
        scene_.environment.zenith = scene_.environment.horizon = scene_.environment.ground =
            background_;
        if (skipped_ > 0)
            scene_.notes.push_back(file_.string() + ": " + std::to_string(skipped_) +
                                   " triangle(s) of polygons without area left out");
        if (insideOnly_)
            scene_.notes.push_back(file_.string() +
                                   ": negative radii (inside only) are drawn two-sided");
        finalizeScene(scene_);
        scene_.defaults.accel = defaultAccel(scene_);
    }

    Tokens tokens_;
    fs::path file_;
    NffOptions options_;
    Scene scene_;
    bool viewpoint_ = false;
    glm::dvec3 from_{0}, at_{0, 0, 1}, up_{0, 1, 0};
    float fovY_ = 0;
    dev::Float3 background_{0, 0, 0};
    std::map<FillLine, int> materialIndex_;
    int material_ = -1;
    std::vector<Tri> tris_, normals_;
    std::vector<int> triMaterial_;
    int skipped_ = 0;
    bool insideOnly_ = false;
};

}  // namespace

NffOptions defaultNffOptions() {
    NffOptions o;
    if (const char* s = std::getenv("RTLAB_NFF_CONE_SEGMENTS")) {
        char* end = nullptr;
        const long k = std::strtol(s, &end, 10);
        if (end == s || *end != '\0' || k < 3 || k > 1024)
            throw Error(std::string("RTLAB_NFF_CONE_SEGMENTS=") + printable(s) +
                            ": must be an integer in 3..1024",
                        FailureKind::InvalidOption);
        o.coneSegments = int(k);
    }
    return o;
}

bool isNffFile(const fs::path& path) {
    std::string ext = path.extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext == ".nff";
}

Scene parseNff(const std::string& text, const fs::path& file, const NffOptions& options) {
    if (options.coneSegments < 3 || options.coneSegments > 1024)
        throw Error(
            "NFF cone segments must be in 3..1024, got " + std::to_string(options.coneSegments),
            FailureKind::InvalidOption);
    try {
        return Parser(text, file, options).parse();
    } catch (const std::bad_alloc&) {
        throw Error(file.string() + ": out of memory");
    }
}

Scene loadNff(const fs::path& path, const NffOptions& options) {
    return parseNff(readTextFile(path), path, options);
}

}  // namespace rt
