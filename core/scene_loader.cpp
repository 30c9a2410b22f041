// rtlab — scene files: JSON (format and rules in scenes/README.md) or a bare OBJ, glTF or PLY
// model, into rt::Scene.
// Every rejection is one line, "<file>: <json pointer>: <reason>", thrown as rt::Error; the
// checks run before anything reaches a device, so kernels may trust the records.
#include "core/scene_loader.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <glm/gtc/matrix_transform.hpp>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "core/accel.h"
#include "core/error.h"
#include "core/model_loader.h"
#include "core/nff_loader.h"
#include "core/obj_loader.h"

namespace rt {
namespace {

namespace fs = std::filesystem;
// Not ordered_json: its inserts are linear, so an object of many keys (a scene may name up to
// RT_MAX_MATERIALS materials) parses in quadratic time. The parser records the material names in
// file order instead.
using Json = nlohmann::json;

constexpr std::size_t kMaxSpheres = 1'000'000;
constexpr std::size_t kMaxPlanes = 1'000;
// As many as spheres: a wall of small meshes places one per object (scripts/make-map.py).
constexpr std::size_t kMaxMeshes = 1'000'000;
constexpr std::size_t kMaxTriangles = 50'000'000;
constexpr int kMaxCubemapSize = 4096;
constexpr std::size_t kAny = ~std::size_t(0);  // no size limit for Node::array
constexpr float kDegrees = 3.14159265358979f / 180.f;

dev::Float3 f3(const glm::vec3& v) { return {v.x, v.y, v.z}; }
glm::vec3 v3(const dev::Float3& f) { return {f.x, f.y, f.z}; }

std::string num(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

// Keeps a message on one printable line.
std::string printable(std::string s) {
    for (char& c : s)
        if (c < 32 || c > 126) c = '?';
    return s;
}

std::string escapeKey(const std::string& key) {  // RFC 6901
    std::string out;
    for (char c : key) out += c == '~' ? "~0" : c == '/' ? "~1" : std::string(1, c);
    return out;
}

std::size_t editDistance(std::string_view a, std::string_view b) {
    std::vector<std::size_t> row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
        std::size_t diag = row[0];
        row[0] = i;
        for (std::size_t j = 1; j <= b.size(); ++j) {
            std::size_t up = row[j];
            row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] != b[j - 1])});
            diag = up;
        }
    }
    return row[b.size()];
}

// " (did you mean 'radius'?)" when a candidate is a typo away or shares a 4-letter prefix.
template <typename Names>
std::string suggestion(const std::string& name, const Names& candidates) {
    for (const auto& c : candidates) {
        std::string_view cand(c);
        std::size_t prefix = 0;
        while (prefix < name.size() && prefix < cand.size() && name[prefix] == cand[prefix])
            ++prefix;
        if (editDistance(name, cand) <= 2 || prefix >= 4)
            return " (did you mean '" + std::string(cand) + "'?)";
    }
    return "";
}

// "line L, column C" of byte offset `at` (0-based), as nlohmann counts them.
std::string lineColumn(const std::string& text, std::size_t at) {
    at = std::min(at, text.size());
    std::size_t line = 1, lineStart = 0;
    for (std::size_t i = 0; i < at; ++i)
        if (text[i] == '\n') ++line, lineStart = i + 1;
    return "line " + std::to_string(line) + ", column " + std::to_string(at - lineStart + 1);
}

// nlohmann's DOM builder plus what it lacks: duplicate keys are errors (nlohmann keeps the last
// one silently), and the keys of the top-level "materials" object are recorded in file order.
// (The DOM *callback* parser would also do, but it rescans the parent container at every
// object end: quadratic in the number of spheres or materials.)
class CheckedSax : public nlohmann::detail::json_sax_dom_parser<Json> {
    using Base = nlohmann::detail::json_sax_dom_parser<Json>;

  public:
    CheckedSax(Json& root, const std::string& file, std::vector<std::string>* materialOrder)
        : Base(root, true), file_(file), materialOrder_(materialOrder) {}

    bool null() { return value() && Base::null(); }
    bool boolean(bool v) { return value() && Base::boolean(v); }
    bool number_integer(Json::number_integer_t v) { return value() && Base::number_integer(v); }
    bool number_unsigned(Json::number_unsigned_t v) { return value() && Base::number_unsigned(v); }
    bool number_float(Json::number_float_t v, const std::string& s) {
        return value() && Base::number_float(v, s);
    }
    bool string(std::string& v) { return value() && Base::string(v); }
    bool binary(Json::binary_t& v) { return value() && Base::binary(v); }
    bool start_object(std::size_t n) {
        value();
        stack_.push_back({false, 0, 0, {}, {}});
        return Base::start_object(n);
    }
    bool start_array(std::size_t n) {
        value();
        stack_.push_back({true, 0, 0, {}, {}});
        return Base::start_array(n);
    }
    bool end_object() {
        stack_.pop_back();
        return Base::end_object();
    }
    bool end_array() {
        stack_.pop_back();
        return Base::end_array();
    }
    bool key(std::string& k) {
        Frame& top = stack_.back();
        top.key = k;
        if (!top.keys.insert(k).second)
            throw Error(file_ + ": " + pointer() + ": duplicate key '" + printable(k) + "'");
        if (stack_.size() == 2 && stack_[0].key == "materials") materialOrder_->push_back(k);
        return Base::key(k);
    }

  private:
    struct Frame {
        bool array;
        std::size_t index, next;  // arrays: the current element, the next one
        std::string key;          // objects: the current key, and all keys so far
        std::set<std::string> keys;
    };

    bool value() {  // a value starts: inside an array it takes the next index
        if (!stack_.empty() && stack_.back().array) stack_.back().index = stack_.back().next++;
        return true;
    }
    std::string pointer() const {  // of the innermost container
        std::string p;
        for (std::size_t i = 0; i + 1 < stack_.size(); ++i)
            p += "/" +
                 (stack_[i].array ? std::to_string(stack_[i].index) : escapeKey(stack_[i].key));
        return p.empty() ? std::string("/") : p;
    }

    const std::string& file_;
    std::vector<std::string>* materialOrder_;
    std::vector<Frame> stack_;
};

// Parses JSON (comments allowed) into `json`; syntax errors name the line and column.
Json parseJson(const std::string& file, const std::string& text,
               std::vector<std::string>* materialOrder) {
    Json json;
    try {
        CheckedSax sax(json, file, materialOrder);
        Json::sax_parse(text, &sax, Json::input_format_t::json, true, /*ignore_comments=*/true);
        return json;
    } catch (const Json::parse_error& e) {
        std::string what = e.what();
        std::size_t at = what.find(": ", what.find("parse error"));
        std::string reason = at == std::string::npos ? what : what.substr(at + 2);
        throw Error(file + ": " + lineColumn(text, e.byte ? e.byte - 1 : 0) + ": " +
                    printable(reason));
    } catch (const Json::exception& e) {  // number overflow: no position, so find the token
        std::string what = e.what();
        std::size_t q = what.find('\'');
        std::string token =
            q == std::string::npos ? "" : what.substr(q + 1, what.rfind('\'') - q - 1);
        std::size_t at = token.empty() ? std::string::npos : text.find(token);
        std::string where = at == std::string::npos ? "" : lineColumn(text, at) + ": ";
        throw Error(file + ": " + where + printable(what.substr(what.find(']') + 2)));
    }
}

// A JSON value with its pointer; every accessor checks type and range and fails with the
// pointer.
class Node {
  public:
    Node(const Json& j, std::string ptr, const std::string& file)
        : j_(&j), ptr_(std::move(ptr)), file_(&file) {}

    [[noreturn]] void fail(const std::string& reason) const {
        throw Error(*file_ + ": " + (ptr_.empty() ? "/" : ptr_) + ": " + reason);
    }
    const Json& json() const { return *j_; }
    const std::string& pointer() const { return ptr_; }

    // An object whose keys all come from `allowed`.
    const Node& object(std::initializer_list<std::string_view> allowed) const {
        if (!j_->is_object()) fail(std::string("must be an object, got ") + j_->type_name());
        for (const auto& [key, value] : j_->items()) {
            bool known = false;
            for (std::string_view a : allowed) known |= key == a;
            if (!known) fail("unknown key '" + printable(key) + "'" + suggestion(key, allowed));
        }
        return *this;
    }
    bool has(std::string_view key) const { return j_->contains(key); }
    Node at(std::string_view key) const {
        auto it = j_->find(key);
        if (it == j_->end()) fail("missing required key '" + std::string(key) + "'");
        return Node(*it, ptr_ + "/" + escapeKey(std::string(key)), *file_);
    }
    template <typename T, typename F>
    T opt(std::string_view key, T fallback, F read) const {
        return has(key) ? read(at(key)) : fallback;
    }

    std::size_t array(std::size_t maxSize, const char* what) const {
        if (!j_->is_array()) fail(std::string("must be an array, got ") + j_->type_name());
        if (j_->size() > maxSize)
            fail("too many " + std::string(what) + ": " + std::to_string(j_->size()) +
                 " (at most " + std::to_string(maxSize) + ")");
        return j_->size();
    }
    Node operator[](std::size_t i) const {
        return Node((*j_)[i], ptr_ + "/" + std::to_string(i), *file_);
    }

    float real() const {
        if (!j_->is_number()) fail(std::string("must be a number, got ") + j_->type_name());
        double v = j_->get<double>();
        if (!std::isfinite(float(v))) fail("must be a finite 32-bit float, got " + num(v));
        return float(v);
    }
    float realIn(float lo, float hi) const {
        float v = real();
        if (v < lo || v > hi) fail("must be in [" + num(lo) + ", " + num(hi) + "], got " + num(v));
        return v;
    }
    float positive() const {
        float v = real();
        if (!(v > 0.f)) fail("must be > 0, got " + num(v));
        return v;
    }
    float nonNegative() const {
        float v = real();
        if (v < 0.f) fail("must be >= 0, got " + num(v));
        return v;
    }
    int integer(int lo, int hi) const {
        double v = real();
        if (v != std::floor(v)) fail("must be an integer, got " + num(v));
        if (v < lo || v > hi)
            fail("must be in " + std::to_string(lo) + ".." + std::to_string(hi) + ", got " +
                 num(v));
        return int(v);
    }
    bool boolean() const {
        if (!j_->is_boolean()) fail(std::string("must be true or false, got ") + j_->type_name());
        return j_->get<bool>();
    }
    std::string string() const {
        if (!j_->is_string()) fail(std::string("must be a string, got ") + j_->type_name());
        return j_->get<std::string>();
    }
    dev::Float3 vec3() const {
        if (!j_->is_array() || j_->size() != 3)
            fail("must be an array of 3 numbers, got " +
                 (j_->is_array() ? "an array of " + std::to_string(j_->size())
                                 : std::string(j_->type_name())));
        return {(*this)[0].real(), (*this)[1].real(), (*this)[2].real()};
    }
    dev::Float3 color() const {  // RGB, each >= 0 (lights may exceed 1)
        vec3();
        return {(*this)[0].nonNegative(), (*this)[1].nonNegative(), (*this)[2].nonNegative()};
    }
    glm::vec3 direction() const {  // non-zero, returned unit length
        glm::dvec3 d(v3(vec3()));
        double len = glm::length(d);
        if (!(len > 0.0) || !std::isfinite(len)) fail("must be a non-zero vector");
        return glm::vec3(d / len);
    }

  private:
    const Json* j_;
    std::string ptr_;
    const std::string* file_;
};

float readReal(const Node& n) { return n.real(); }
float readPositive(const Node& n) { return n.positive(); }
float readNonNegative(const Node& n) { return n.nonNegative(); }
float readUnit(const Node& n) { return n.realIn(0.f, 1.f); }
dev::Float3 readColor(const Node& n) { return n.color(); }
dev::Float3 readVec3(const Node& n) { return n.vec3(); }

class Loader {
  public:
    Loader(const fs::path& path, const ImageReader& readImage)
        : path_(path), file_(path.string()), dir_(path.parent_path()), readImage_(readImage) {}

    Scene load() {
        const std::string text = readTextFile(path_);
        const Json json = parseJson(file_, text, &materialOrder_);
        Node root(json, "", file_);
        root.object({"description", "camera", "materials", "spheres", "planes", "triangles",
                     "meshes", "lights", "environment", "render"});
        if (root.has("description")) root.at("description").string();
        scene_.name = path_.stem().string();
        scene_.source = path_;
        camera(root.at("camera"));
        if (root.has("materials")) materials(root.at("materials"));
        if (root.has("spheres")) spheres(root.at("spheres"));
        if (root.has("planes")) planes(root.at("planes"));
        if (root.has("triangles")) triangles(root.at("triangles"));
        if (root.has("meshes")) meshes(root.at("meshes"));
        if (root.has("lights")) lights(root.at("lights"));
        if (root.has("environment")) environment(root.at("environment"));
        if (root.has("render")) render(root.at("render"));
        finalizeScene(scene_);
        if (!accelGiven_) scene_.defaults.accel = defaultAccel(scene_);
        return std::move(scene_);
    }

  private:
    void camera(const Node& n) {
        n.object({"position", "yaw", "pitch", "look_at", "fov"});
        dev::Camera& c = scene_.camera;
        c.position = n.at("position").vec3();
        if (n.has("look_at")) {
            if (n.has("yaw") || n.has("pitch")) n.fail("give either 'look_at' or 'yaw'/'pitch'");
            Node at = n.at("look_at");
            glm::dvec3 d = glm::dvec3(v3(at.vec3())) - glm::dvec3(v3(c.position));
            if (glm::length(d) == 0.0) at.fail("must differ from the camera position");
            d = glm::normalize(d);
            // Inverts SHADING.md section 1 for the centre ray: d = (cos p sin y, sin p, cos p cos
            // y).
            c.pitch = float(std::asin(std::clamp(d.y, -1.0, 1.0)));
            c.yaw = float(std::atan2(d.x, d.z));
        } else {
            c.yaw = n.opt("yaw", 0.f, readReal) * kDegrees;
            c.pitch =
                n.opt("pitch", 0.f, [](const Node& p) { return p.realIn(-90, 90); }) * kDegrees;
        }
        float fov = n.opt("fov", 45.f, [](const Node& f) {
            float v = f.real();
            if (!(v > 0.f && v < 180.f)) f.fail("must be in (0, 180) degrees, got " + num(v));
            return v;
        });
        c.fovY = fov * kDegrees;
    }

    void materials(const Node& n) {
        if (!n.json().is_object())
            n.fail(std::string("must be an object, got ") + n.json().type_name());
        if (n.json().size() > RT_MAX_MATERIALS)
            n.fail("too many materials: " + std::to_string(n.json().size()) + " (at most " +
                   std::to_string(RT_MAX_MATERIALS) + ")");
        for (const std::string& name : materialOrder_) {
            Node m(n.json().at(name), n.pointer() + "/" + escapeKey(name), file_);
            if (name.empty()) m.fail("material name must not be empty");
            m.object({"ambient", "diffuse", "specular", "exponent", "reflectance", "opacity", "ior",
                      "pattern", "octaves", "scale", "diffuse2", "bump"});
            dev::Material mat{};
            mat.ambient = m.opt("ambient", dev::Float3{0, 0, 0}, readColor);
            mat.diffuse = m.opt("diffuse", dev::Float3{0.8f, 0.8f, 0.8f}, readColor);
            mat.specular = m.opt("specular", dev::Float3{0, 0, 0}, readColor);
            mat.exponent = m.opt("exponent", 32.f, readNonNegative);
            mat.reflectance = m.opt("reflectance", 0.f, readUnit);
            mat.opacity = m.opt("opacity", 1.f, readUnit);
            mat.ior = m.opt("ior", 1.f, readPositive);
            procedural(m, mat);
            scene_.materials.push_back(mat);
            materialIndex_[name] = int(scene_.materialNames.size());
            scene_.materialNames.push_back(name);
        }
    }

    // The procedural material keys (scenes/README.md, "Procedural materials").
    static void procedural(const Node& m, dev::Material& mat) {
        static const char* const names[] = {"none", "checker", "marble", "wood", "granite", "bump"};
        mat.pattern = m.opt("pattern", RT_PATTERN_NONE, [](const Node& p) {
            const std::string s = p.string();
            for (int k = 0; k < 6; ++k)
                if (s == names[k]) return k;
            p.fail("unknown pattern '" + printable(s) +
                   "' (none, checker, marble, wood, granite or bump)");
        });
        mat.octaves =
            m.opt("octaves", 4, [](const Node& o) { return o.integer(0, RT_MAX_OCTAVES); });
        mat.patternScale = m.opt("scale", 1.f, readPositive);
        mat.diffuse2 = m.opt("diffuse2", dev::Float3{0.1f, 0.1f, 0.1f}, readColor);
        mat.bump = m.opt("bump", 0.5f, readNonNegative);
    }

    int material(const Node& obj) {
        Node n = obj.at("material");
        std::string name = n.string();
        auto it = materialIndex_.find(name);
        if (it != materialIndex_.end()) return it->second;
        n.fail("unknown material '" + printable(name) + "'" +
               suggestion(name, scene_.materialNames));
    }

    void spheres(const Node& list) {
        for (std::size_t i = 0, n = list.array(kMaxSpheres, "spheres"); i < n; ++i) {
            Node s = list[i];
            s.object({"center", "radius", "material"});
            dev::Sphere sphere{};
            sphere.center = s.at("center").vec3();
            sphere.radius = s.at("radius").positive();
            sphere.material = material(s);
            scene_.spheres.push_back(sphere);
        }
    }

    void planes(const Node& list) {
        for (std::size_t i = 0, n = list.array(kMaxPlanes, "planes"); i < n; ++i) {
            Node p = list[i];
            p.object({"normal", "offset", "point", "material"});
            dev::Plane plane{};
            glm::vec3 normal = p.at("normal").direction();
            plane.normal = f3(normal);
            if (p.has("offset") == p.has("point"))
                p.fail(p.has("offset") ? "give either 'offset' or 'point', not both"
                                       : "missing required key 'offset' (or 'point')");
            if (p.has("offset")) {
                plane.offset = p.at("offset").real();
            } else {
                plane.offset = glm::dot(normal, v3(p.at("point").vec3()));
                if (!std::isfinite(plane.offset)) p.at("point").fail("offset overflows");
            }
            plane.material = material(p);
            scene_.planes.push_back(plane);
        }
    }

    void addTriangles(std::size_t count, const Node& where) {
        if (scene_.triangles.size() + count > kMaxTriangles)
            where.fail("too many triangles: " + std::to_string(scene_.triangles.size() + count) +
                       " (at most " + std::to_string(kMaxTriangles) + ")");
    }

    // Loose triangles form one implicit mesh, before the OBJ meshes.
    void triangles(const Node& list) {
        const std::size_t n = list.array(kMaxTriangles, "triangles");
        addTriangles(n, list);
        for (std::size_t i = 0; i < n; ++i) {
            Node t = list[i];
            t.object({"vertices", "normals", "material"});
            Node vs = t.at("vertices");
            if (std::size_t k = vs.array(kAny, "vertices"); k != 3)
                vs.fail("must be an array of 3 vertices, got " + std::to_string(k));
            glm::vec3 v[3] = {v3(vs[0].vec3()), v3(vs[1].vec3()), v3(vs[2].vec3())};
            glm::dvec3 cross = glm::cross(glm::dvec3(v[1] - v[0]), glm::dvec3(v[2] - v[0]));
            double len = glm::length(cross);
            if (!(len > 0.0) || !std::isfinite(len)) vs.fail("degenerate triangle (zero area)");
            glm::vec3 n[3];
            n[0] = n[1] = n[2] = glm::vec3(cross / len);
            if (t.has("normals")) {
                Node ns = t.at("normals");
                if (std::size_t k = ns.array(kAny, "normals"); k != 3)
                    ns.fail("must be an array of 3 normals, got " + std::to_string(k));
                for (int k = 0; k < 3; ++k) n[k] = ns[k].direction();
            }
            scene_.triangles.push_back(
                {f3(v[0]), f3(v[1]), f3(v[2]), f3(n[0]), f3(n[1]), f3(n[2]), material(t), 0});
        }
        if (n > 0) scene_.meshes.push_back({0, int(n), -1, 0, {}, {}, {}, 0.f, {}});
    }

    // A model file's triangles: three positions and normals per triangle.
    struct Geometry {
        std::vector<glm::vec3> positions, normals;
    };

    // OBJ through core/obj_loader, glTF and PLY through core/model_loader (in world space, the
    // file's node transforms applied); the file's materials, cameras and lights are not used.
    static Geometry geometry(const fs::path& file) {
        if (isModelFile(file)) {
            Model model = loadModel(file);
            return {std::move(model.positions), std::move(model.normals)};
        }
        ObjMesh obj = loadObj(file);
        return {std::move(obj.positions), std::move(obj.normals)};
    }

    void meshes(const Node& list) {
        std::map<std::string, Geometry> cache;  // one parse per file, however often placed
        for (std::size_t i = 0, n = list.array(kMaxMeshes, "meshes"); i < n; ++i) {
            Node m = list[i];
            m.object({"file", "material", "transform"});
            Node fileNode = m.at("file");
            fs::path file = dir_ / fileNode.string();
            const int mat = material(m);
            glm::mat4 xf = m.has("transform") ? transform(m.at("transform")) : glm::mat4(1.f);
            auto it = cache.find(file.string());
            if (it == cache.end()) {
                try {
                    it = cache.emplace(file.string(), geometry(file)).first;
                } catch (const Error& e) {
                    fileNode.fail(e.what());
                }
            }
            const Geometry& obj = it->second;
            addTriangles(obj.positions.size() / 3, m);
            glm::mat3 normalXf = glm::transpose(glm::inverse(glm::mat3(xf)));
            dev::MeshInstance inst{};
            inst.firstTriangle = int(scene_.triangles.size());
            inst.triangleCount = int(obj.positions.size() / 3);
            for (std::size_t t = 0; t < obj.positions.size(); t += 3) {
                dev::Triangle tri{};
                dev::Float3* v[6] = {&tri.v0, &tri.v1, &tri.v2, &tri.n0, &tri.n1, &tri.n2};
                for (int k = 0; k < 3; ++k) {
                    glm::vec3 p = glm::vec3(xf * glm::vec4(obj.positions[t + k], 1.f));
                    glm::vec3 nn = glm::normalize(normalXf * obj.normals[t + k]);
                    if (!std::isfinite(p.x + p.y + p.z) || !std::isfinite(nn.x + nn.y + nn.z))
                        m.at("transform").fail("transformed mesh has non-finite coordinates");
                    *v[k] = f3(p);
                    *v[3 + k] = f3(nn);
                }
                tri.material = mat;
                tri.mesh = int(scene_.meshes.size());
                scene_.triangles.push_back(tri);
            }
            scene_.meshes.push_back(inst);
        }
    }

    // T * Rz * Ry * Rx * S: scale, then rotate about x, y, z (degrees), then translate.
    glm::mat4 transform(const Node& n) {
        n.object({"translate", "rotate", "scale"});
        glm::vec3 scale(1.f);
        if (n.has("scale")) {
            Node s = n.at("scale");
            scale = s.json().is_number() ? glm::vec3(s.real()) : v3(s.vec3());
            if (scale.x == 0.f || scale.y == 0.f || scale.z == 0.f) s.fail("must be non-zero");
        }
        glm::vec3 rotate = v3(n.opt("rotate", dev::Float3{0, 0, 0}, readVec3)) * kDegrees;
        glm::mat4 m =
            glm::translate(glm::mat4(1.f), v3(n.opt("translate", dev::Float3{0, 0, 0}, readVec3)));
        m = glm::rotate(m, rotate.z, glm::vec3(0, 0, 1));
        m = glm::rotate(m, rotate.y, glm::vec3(0, 1, 0));
        m = glm::rotate(m, rotate.x, glm::vec3(1, 0, 0));
        return glm::scale(m, scale);
    }

    void lights(const Node& list) {
        const std::size_t n = list.array(kAny, "lights");
        if (n > RT_MAX_LIGHTS)
            list.fail("at most " + std::to_string(RT_MAX_LIGHTS) + " lights, got " +
                      std::to_string(n));
        for (std::size_t i = 0; i < n; ++i) {
            Node l = list[i];
            l.object({"position", "color", "radius"});
            dev::Light light{};
            light.position = l.at("position").vec3();
            light.color = l.opt("color", dev::Float3{1, 1, 1}, readColor);
            light.radius = l.opt("radius", 0.f, readNonNegative);
            scene_.lights.push_back(light);
        }
    }

    void environment(const Node& n) {
        n.object({"sky", "cubemap"});
        if (n.has("sky") == n.has("cubemap"))
            n.fail(n.has("sky") ? "give either 'sky' or 'cubemap', not both"
                                : "missing required key 'sky' (or 'cubemap')");
        Environment& env = scene_.environment;
        if (n.has("sky")) {
            Node s = n.at("sky");
            s.object({"zenith", "horizon", "ground"});
            env.zenith = s.opt("zenith", env.zenith, readColor);
            env.horizon = s.opt("horizon", env.horizon, readColor);
            env.ground = s.opt("ground", env.ground, readColor);
            return;
        }
        Node faces = n.at("cubemap");
        if (faces.array(kAny, "cubemap faces") != 6)
            faces.fail("must list 6 faces (+x, -x, +y, -y, +z, -z), got " +
                       std::to_string(faces.json().size()));
        if (!readImage_) faces.fail("cubemap needs an image reader");
        for (std::size_t i = 0; i < 6; ++i) {
            Node f = faces[i];
            fs::path file = dir_ / f.string();
            Image img;
            try {
                img = readImage_(file);
            } catch (const std::exception& e) {
                std::string what = printable(e.what());
                f.fail(what.find(file.string()) == std::string::npos ? file.string() + ": " + what
                                                                     : what);
            }
            const std::string size = std::to_string(img.width) + "x" + std::to_string(img.height);
            if (img.width <= 0 || img.width != img.height)
                f.fail("face is " + size + ", must be square");
            if (img.width > kMaxCubemapSize)
                f.fail("face is " + size + ", at most " + std::to_string(kMaxCubemapSize));
            if (i > 0 && img.width != env.cubemapSize)
                f.fail("face is " + size + ", but face 0 is " + std::to_string(env.cubemapSize) +
                       "x" + std::to_string(env.cubemapSize));
            if (img.rgb.size() != std::size_t(img.width) * img.height * 3)
                f.fail("image reader returned " + std::to_string(img.rgb.size()) + " floats");
            for (float v : img.rgb)
                if (!std::isfinite(v)) f.fail("face has non-finite texels");
            env.cubemapSize = img.width;
            env.cubemap.insert(env.cubemap.end(), img.rgb.begin(), img.rgb.end());
        }
    }

    void render(const Node& n) {
        n.object({"width", "height", "bounces", "shadow_samples", "aa", "shadow_strength",
                  "adaptive_aa", "accel"});
        RenderOptions& r = scene_.defaults;
        auto range = [](int lo, int hi) {
            return [=](const Node& v) { return v.integer(lo, hi); };
        };
        r.width = n.opt("width", r.width, range(1, 16384));
        r.height = n.opt("height", r.height, range(1, 16384));
        r.bounces = n.opt("bounces", r.bounces, range(0, RT_MAX_BOUNCE_LIMIT));
        r.shadowSamples = n.opt("shadow_samples", r.shadowSamples, range(1, RT_MAX_SHADOW_SAMPLES));
        r.aa = n.opt("aa", r.aa, range(1, 16));
        r.shadowStrength = n.opt("shadow_strength", r.shadowStrength, readUnit);
        r.adaptiveAa =
            n.opt("adaptive_aa", r.adaptiveAa, [](const Node& b) { return b.boolean(); });
        if (n.has("accel")) {
            Node a = n.at("accel");
            std::string name = a.string();
            try {
                r.accel = parseAccel(name);
            } catch (const Error&) {
                a.fail("must be one of none, bv, grid, bvh, wide, cwbvh, got '" + name + "'");
            }
            accelGiven_ = true;
        }
    }

    fs::path path_;
    std::string file_;
    fs::path dir_;
    const ImageReader& readImage_;
    std::vector<std::string> materialOrder_;
    std::unordered_map<std::string, int> materialIndex_;
    Scene scene_;
    bool accelGiven_ = false;  // else the scene gets defaultAccel
};

// An .mtl material as rtlab's: Ka, Kd, Ks and Ns as they are; d as the opacity, with Ni as the
// index of refraction of what shows through; illumination models 3, 5 and 7 (ray-traced
// reflection) make the surface a mirror weighted by Ks's mean.
dev::Material fromObj(const ObjMaterial& m) {
    dev::Material out{};
    out.ambient = f3(m.ambient);
    out.diffuse = f3(m.diffuse);
    out.specular = f3(m.specular);
    out.exponent = m.shininess;
    const bool mirror = m.illum == 3 || m.illum == 5 || m.illum == 7;
    out.reflectance = mirror ? (m.specular.x + m.specular.y + m.specular.z) / 3.f : 0.f;
    out.opacity = m.dissolve;
    out.ior = m.dissolve < 1.f ? m.ior : 1.f;
    return out;
}

// A bare model's scene starts with two materials: `default` (grey) and `ground`; the file's
// own follow (scenes/README.md, "A bare model").
Scene bareModelScene(const fs::path& path) {
    Scene scene;
    scene.name = path.stem().string();
    scene.source = path;
    dev::Material ground{};
    ground.diffuse = {0.5f, 0.5f, 0.5f};
    ground.ambient = {0.05f, 0.05f, 0.05f};
    ground.exponent = 8.f;
    ground.opacity = ground.ior = 1.f;
    scene.materials = {defaultModelMaterial(), ground};
    scene.materialNames = {"default", "ground"};
    return scene;
}

constexpr int kGroundMaterial = 1;

// The rest of a bare model's scene, around its triangles (one mesh): the file's camera, or one
// on -z framing the bounding sphere; the file's lights, or one white point light above, in
// front and to the right; a ground plane just below the lowest point.
void finishBareModel(Scene& scene, const ModelCamera* camera) {
    scene.meshes.push_back({0, int(scene.triangles.size()), -1, 0, {}, {}, {}, 0.f, {}});
    finalizeScene(scene);
    scene.defaults.accel = defaultAccel(scene);
    const dev::MeshInstance& m = scene.meshes[0];
    const glm::vec3 c = v3(m.sphereCenter);
    const float r = std::max(m.sphereRadius, 1e-6f);
    if (camera) {
        // As a JSON look_at (SHADING.md section 1 inverted for the centre ray).
        const glm::dvec3 d(camera->direction);
        const float yaw = float(std::atan2(d.x, d.z));
        const float pitch = float(std::asin(std::clamp(d.y, -1.0, 1.0)));
        scene.camera = {f3(camera->position), yaw, pitch, camera->fovY, {0, 0}};
    } else {
        const float fov = 45.f * kDegrees;
        const float distance = 1.1f * r / std::sin(fov / 2);  // 10% margin around the sphere
        scene.camera = {f3(c - glm::vec3(0, 0, distance)), 0.f, 0.f, fov, {0, 0}};
    }
    if (scene.lights.empty())
        scene.lights.push_back({f3(c + glm::vec3(r, 3 * r, -2 * r)), 0.f, {1, 1, 1}, 0.f});
    scene.planes.push_back({{0, 1, 0}, m.boundsLo.y - 1e-3f * r, kGroundMaterial, {0, 0, 0}});
}

// A bare OBJ: faces with a usemtl that a library defines get that material, the others
// `default`.
Scene wrapObj(const fs::path& path) {
    ObjMesh obj = loadObj(path);
    Scene scene = bareModelScene(path);
    const int firstObjMaterial = int(scene.materials.size());
    for (const ObjMaterial& m : obj.materials) {
        scene.materials.push_back(fromObj(m));
        scene.materialNames.push_back(m.name);
    }
    if (!obj.materialNote.empty()) scene.notes.push_back(path.string() + ": " + obj.materialNote);
    for (std::size_t t = 0; t < obj.positions.size(); t += 3) {
        const auto& p = obj.positions;
        const auto& n = obj.normals;
        const int m = t / 3 < obj.triangleMaterial.size() ? obj.triangleMaterial[t / 3] : -1;
        scene.triangles.push_back({f3(p[t]), f3(p[t + 1]), f3(p[t + 2]), f3(n[t]), f3(n[t + 1]),
                                   f3(n[t + 2]), m < 0 ? 0 : firstObjMaterial + m, 0});
    }
    finishBareModel(scene, nullptr);
    return scene;
}

// A bare glTF or PLY model (core/model_loader.h): its materials, camera and lights where the
// file has them.
Scene wrapModel(const fs::path& path) {
    Model model = loadModel(path);
    Scene scene = bareModelScene(path);
    const int first = int(scene.materials.size());
    scene.materials.insert(scene.materials.end(), model.materials.begin(), model.materials.end());
    scene.materialNames.insert(scene.materialNames.end(), model.materialNames.begin(),
                               model.materialNames.end());
    scene.notes = std::move(model.notes);
    scene.lights = std::move(model.lights);
    const auto& p = model.positions;
    const auto& n = model.normals;
    scene.triangles.reserve(p.size() / 3);
    for (std::size_t t = 0; t < p.size(); t += 3)
        scene.triangles.push_back({f3(p[t]), f3(p[t + 1]), f3(p[t + 2]), f3(n[t]), f3(n[t + 1]),
                                   f3(n[t + 2]), first + model.triangleMaterial[t / 3], 0});
    finishBareModel(scene, model.camera ? &*model.camera : nullptr);
    return scene;
}

std::string lowerExtension(const fs::path& path) {
    std::string ext = path.extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

bool isObj(const fs::path& path) { return lowerExtension(path) == ".obj"; }

// Model formats people try first that rtlab does not read.
void rejectOtherModelFormats(const fs::path& path) {
    static const char* const kOthers[] = {".fbx", ".stl",  ".dae",  ".3ds", ".blend",
                                          ".usd", ".usda", ".usdz", ".x3d"};
    const std::string ext = lowerExtension(path);
    for (const char* other : kOthers)
        if (ext == other)
            throw Error(
                path.string() + ": " + ext.substr(1) +
                " files are not supported; rtlab reads .obj, .gltf, .glb and .ply models "
                "and .json and .nff scenes (convert it, e.g. with assimp export or Blender)");
}

// A file that is not JSON at all (a README, an image given by mistake) is named as such rather
// than with the JSON parser's "syntax error at line 1": JSON's first character past white space
// (and a byte-order mark) starts a value or a comment. JSON that is not an object still reaches
// the loader, which says what it is.
void rejectNonJson(const fs::path& path) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) return;  // a FIFO would block here; the loader refuses it
    std::ifstream in(path, std::ios::binary);
    if (!in) return;  // the loader says why it cannot read it
    char c = 0;
    int seen = 0;
    while (in.get(c) && ++seen < 4096) {
        if (std::isspace(static_cast<unsigned char>(c))) continue;
        if (seen <= 3 && static_cast<unsigned char>(c) >= 0xEF) continue;  // UTF-8 BOM bytes
        if (std::strchr("{[\"-0123456789tfn/", c)) return;
        break;
    }
    if (seen == 0 || !in) return;  // empty: the loader's own message
    throw Error(path.string() +
                ": not a scene file (a scene is a JSON object; rtlab reads .json "
                "and .nff scenes and .obj, .gltf, .glb and .ply models)");
}

}  // namespace

std::string readTextFile(const std::filesystem::path& path) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (fs::is_directory(path, ec)) throw Error(path.string() + ": cannot open: Is a directory");
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) throw Error(path.string() + ": cannot open: " + std::strerror(errno));
    std::string text;
    char buffer[1 << 16];
    std::size_t n;
    while ((n = std::fread(buffer, 1, sizeof buffer, f)) > 0 && text.size() < (256u << 20))
        text.append(buffer, n);
    const bool bad = std::ferror(f);
    const int err = errno;
    std::fclose(f);
    if (bad) throw Error(path.string() + ": cannot read: " + std::strerror(err));
    if (text.size() >= (256u << 20)) throw Error(path.string() + ": file too large (> 256 MiB)");
    return text;
}

Scene loadScene(const std::filesystem::path& path, const ImageReader& readImage) {
    try {
        rejectOtherModelFormats(path);
        if (isObj(path)) return wrapObj(path);
        if (isModelFile(path)) return wrapModel(path);
        if (isNffFile(path)) return loadNff(path);
        rejectNonJson(path);
        return Loader(path, readImage).load();
    } catch (const std::bad_alloc&) {
        throw Error(path.string() + ": out of memory");
    }
}

void finalizeScene(Scene& scene) {
    const std::string who = !scene.source.empty() ? scene.source.string()
                            : !scene.name.empty() ? scene.name
                                                  : std::string("scene");
    auto fail = [&](const std::string& reason) { throw Error(who + ": " + reason); };
    if (scene.triangles.size() > kMaxTriangles)
        fail("too many triangles: " + std::to_string(scene.triangles.size()));
    if (scene.lights.size() > RT_MAX_LIGHTS)
        fail("at most " + std::to_string(RT_MAX_LIGHTS) + " lights, got " +
             std::to_string(scene.lights.size()));
    if (scene.materials.size() > RT_MAX_MATERIALS)
        fail("too many materials: " + std::to_string(scene.materials.size()));
    // Triangles without meshes (built by hand): one mesh holds them all.
    if (scene.meshes.empty() && !scene.triangles.empty())
        scene.meshes.push_back({0, int(scene.triangles.size()), -1, 0, {}, {}, {}, 0.f, {}});
    const int materialCount = int(scene.materials.size());
    auto checkMaterial = [&](int m, const char* what, std::size_t i) {
        if (m < 0 || m >= materialCount)
            fail(std::string(what) + " " + std::to_string(i) + " has material " +
                 std::to_string(m) + " of " + std::to_string(materialCount));
    };
    for (std::size_t i = 0; i < scene.spheres.size(); ++i)
        checkMaterial(scene.spheres[i].material, "sphere", i);
    for (std::size_t i = 0; i < scene.planes.size(); ++i)
        checkMaterial(scene.planes[i].material, "plane", i);

    std::vector<char> covered(scene.triangles.size(), 0);
    for (std::size_t mi = 0; mi < scene.meshes.size(); ++mi) {
        dev::MeshInstance& m = scene.meshes[mi];
        if (m.firstTriangle < 0 || m.triangleCount < 0 ||
            std::size_t(m.firstTriangle) + m.triangleCount > scene.triangles.size())
            fail("mesh " + std::to_string(mi) + " covers triangles outside the scene");
        glm::vec3 lo(INFINITY), hi(-INFINITY);
        for (int t = m.firstTriangle; t < m.firstTriangle + m.triangleCount; ++t) {
            dev::Triangle& tri = scene.triangles[t];
            if (covered[t]++) fail("triangle " + std::to_string(t) + " is in two meshes");
            checkMaterial(tri.material, "triangle", std::size_t(t));
            tri.mesh = int(mi);
            for (const dev::Float3* v : {&tri.v0, &tri.v1, &tri.v2}) {
                glm::vec3 p = v3(*v);
                if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
                    fail("triangle " + std::to_string(t) + " has a non-finite vertex");
                lo = glm::min(lo, p);
                hi = glm::max(hi, p);
            }
        }
        if (m.triangleCount == 0) lo = hi = glm::vec3(0.f);
        glm::vec3 center = (lo + hi) * 0.5f;
        float radius = 0.f;
        for (int t = m.firstTriangle; t < m.firstTriangle + m.triangleCount; ++t) {
            const dev::Triangle& tri = scene.triangles[t];
            for (const dev::Float3* v : {&tri.v0, &tri.v1, &tri.v2})
                radius = std::max(radius, glm::length(v3(*v) - center));
        }
        m.boundsLo = f3(lo);
        m.boundsHi = f3(hi);
        m.sphereCenter = f3(center);
        m.sphereRadius = radius;
        m.bvhRoot = -1;
    }
    for (std::size_t t = 0; t < covered.size(); ++t)
        if (!covered[t]) fail("triangle " + std::to_string(t) + " belongs to no mesh");
}

}  // namespace rt
