// rtlab bench — reading sweep files (format: bench/sweeps/README.md) and expanding them into cells.
#include "bench/sweep_config.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "core/accel.h"
#include "core/error.h"

namespace rt::bench {
namespace fs = std::filesystem;

namespace {

std::string trim(const std::string& s) {
    size_t a = s.find_first_not_of(" \t\r"), b = s.find_last_not_of(" \t\r");
    return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}

std::vector<std::string> words(const std::string& s) {
    std::vector<std::string> out;
    std::string w;
    for (char c : s) {
        if (c == ' ' || c == '\t' || c == ',') {
            if (!w.empty()) out.push_back(w);
            w.clear();
        } else {
            w += c;
        }
    }
    if (!w.empty()) out.push_back(w);
    return out;
}

// Parses one key's value; `where` prefixes errors ("bench/sweeps/full:12").
class ValueParser {
  public:
    explicit ValueParser(std::string where) : where_(std::move(where)) {}
    [[noreturn]] void fail(const std::string& why) const {
        throw Error(where_ + ": " + why, FailureKind::InvalidOption);
    }

    int integer(const std::string& w, int lo, int hi) const { return int(wholeNumber(w, lo, hi)); }
    // A whole number in lo..hi, whose range may pass an int's (a pipeline option's).
    long long wholeNumber(const std::string& w, long long lo, long long hi) const {
        size_t used = 0;
        long long v = 0;
        try {
            v = std::stoll(w, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used != w.size() || w.empty()) fail("'" + w + "' is not an integer");
        if (v < lo || v > hi)
            fail(w + " is out of range " + std::to_string(lo) + ".." + std::to_string(hi));
        return v;
    }
    // "1 2 4", "0..8", or "default" (empty list).
    std::vector<int> integers(const std::string& value, int lo, int hi) const {
        std::vector<int> out;
        for (const std::string& w : words(value)) {
            if (w == "default") continue;
            size_t dots = w.find("..");
            if (dots == std::string::npos) {
                out.push_back(integer(w, lo, hi));
                continue;
            }
            int a = integer(w.substr(0, dots), lo, hi), b = integer(w.substr(dots + 2), lo, hi);
            if (b < a) fail("range " + w + " runs backwards");
            for (int i = a; i <= b; ++i) out.push_back(i);
        }
        return out;
    }
    // "4096", "64K", "512M", "2G".
    size_t bytes(const std::string& value) const {
        static const std::regex re("([0-9]+(\\.[0-9]+)?)([KMG]?)");
        std::smatch m;
        if (!std::regex_match(value, m, re)) fail("'" + value + "': expected bytes such as 512M");
        double scale = m[3] == "K"   ? 1024.0
                       : m[3] == "M" ? 1048576.0
                       : m[3] == "G" ? 1073741824.0
                                     : 1;
        return size_t(std::llround(std::stod(m[1]) * scale));
    }
    double number(const std::string& w, double lo, double hi) const {
        size_t used = 0;
        double v = 0;
        try {
            v = std::stod(w, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used != w.size() || w.empty() || !std::isfinite(v)) fail("'" + w + "' is not a number");
        if (v < lo || v > hi)
            fail(w + " is out of range " + std::to_string(int(lo)) + ".." +
                 std::to_string(int(hi)));
        return v;
    }
    bool boolean(const std::string& value) const {
        if (value == "yes" || value == "true" || value == "on") return true;
        if (value == "no" || value == "false" || value == "off") return false;
        fail("expected yes or no, got '" + value + "'");
    }
    template <typename F>
    auto wrap(F&& f) const {
        try {
            return f();
        } catch (const Error& e) {
            fail(e.what());
        }
    }

  private:
    std::string where_;
};

const std::set<std::string> kGroupKeys = {
    "scenes",     "pipelines", "sizes",         "bounces",       "shadow-samples",
    "aa",         "accel",     "memory-budget", "adaptive",      "images",
    "repeats",    "warmup",    "count-rays",    "max-launch-ms", "stop-after-failure",
    "max-frame-s"};
const std::set<std::string> kTopKeys = {"reference-bounces", "reference-shadow-samples",
                                        "reference-aa", "cl-options"};

void applyGroupKey(SweepGroup& g, const std::string& key, const std::string& value,
                   const ValueParser& p) {
    if (key == "scenes") {
        g.scenes = words(value);
    } else if (key == "pipelines") {
        g.pipelines.clear();
        for (const std::string& w : words(value)) {
            const PipelineInfo& info =
                p.wrap([&]() -> const PipelineInfo& { return pipelineInfo(w); });
            if (info.reference)
                p.fail("the " + info.name + " reference is not a measured pipeline");
            g.pipelines.push_back(info.name);
        }
    } else if (key == "sizes") {
        g.sizes.clear();
        for (const std::string& w : words(value)) {
            if (w == "default") continue;
            static const std::regex re("([0-9]{1,5})x([0-9]{1,5})");
            std::smatch m;
            if (!std::regex_match(w, m, re)) p.fail("size '" + w + "': expected WIDTHxHEIGHT");
            g.sizes.emplace_back(p.integer(m[1], 1, 16384), p.integer(m[2], 1, 16384));
        }
    } else if (key == "bounces") {
        g.bounces = p.integers(value, 0, RT_MAX_BOUNCE_LIMIT);
    } else if (key == "shadow-samples") {
        g.shadowSamples = p.integers(value, 1, RT_MAX_SHADOW_SAMPLES);
    } else if (key == "aa") {
        g.aa = p.integers(value, 1, 16);
    } else if (key == "accel") {
        g.accels.clear();
        for (const std::string& w : words(value))
            if (w != "default") g.accels.push_back(p.wrap([&] { return parseAccel(w); }));
    } else if (key == "memory-budget") {
        g.memoryBudget = value == "default" ? 0 : p.bytes(value);
    } else if (key == "adaptive") {
        g.adaptive = p.boolean(value);
    } else if (key == "images") {
        g.images = p.boolean(value);
    } else if (key == "repeats") {
        g.repeats = p.integer(value, 1, 1000);
    } else if (key == "warmup") {
        g.warmup = p.integer(value, 0, 100);
    } else if (key == "count-rays") {
        g.countRays = p.boolean(value) ? 1 : 0;
    } else if (key == "max-launch-ms") {
        g.maxLaunchMs = p.number(value, 0, 1e6);
    } else if (const PipelineOption* opt = pipelineRegistry().findSweepOption(key)) {
        // Numbers are checked against the range as the other integer keys are, "default"
        // standing for the declared default; names by the declaration (naming its flag).
        if (opt->type == PipelineOption::Type::Choice)
            p.wrap([&] { opt->set(g.pipelineOptions, value); });
        else if (value == "default")
            g.pipelineOptions.reset(opt->name);
        else
            opt->set(g.pipelineOptions, p.wholeNumber(value, opt->min, opt->max));
    } else if (key == "stop-after-failure") {
        g.stopAfterFailure = p.boolean(value);
    } else if (key == "max-frame-s") {
        g.maxFrameS = p.number(value, 0, 1e6);
    }
}

// "|Qdevice|P4096": each pipeline option that is not at its default, in registration order.
std::string pipelineOptionsKey(const PipelineOptionValues& values) {
    std::string k;
    for (const PipelineOption* opt : pipelineRegistry().options())
        if (!opt->isDefault(values)) k += "|" + opt->cellTag + opt->text(opt->value(values));
    return k;
}

}  // namespace

SweepConfig parseSweep(const std::string& text, const fs::path& path) {
    SweepConfig c;
    c.path = path;
    c.name = path.stem().string();
    c.text = text;
    SweepGroup defaults;  // keys before the first [group]
    std::vector<std::vector<std::pair<std::string, std::string>>> groupKeys;
    std::vector<std::string> groupNames;
    std::istringstream in(text);
    std::string line;
    for (int n = 1; std::getline(in, line); ++n) {
        ValueParser p(path.string() + ":" + std::to_string(n));
        line = trim(line.substr(0, line.find('#')));
        if (line.empty()) continue;
        if (line.front() == '[') {
            if (line.back() != ']' || line.size() < 3) p.fail("expected [group-name]");
            groupNames.push_back(trim(line.substr(1, line.size() - 2)));
            groupKeys.emplace_back();
            continue;
        }
        size_t eq = line.find('=');
        if (eq == std::string::npos) p.fail("expected 'key = value' or '[group]'");
        std::string key = trim(line.substr(0, eq)), value = trim(line.substr(eq + 1));
        bool top = kTopKeys.count(key),
             group = kGroupKeys.count(key) || pipelineRegistry().findSweepOption(key);
        if (!top && !group) p.fail("unknown key '" + key + "' (see bench/sweeps/README.md)");
        if (top) {
            if (!groupNames.empty()) p.fail("'" + key + "' belongs before the first [group]");
            if (key == "reference-bounces")
                c.referenceBounces = p.integer(value, 0, RT_MAX_BOUNCE_LIMIT);
            if (key == "reference-shadow-samples")
                c.referenceShadowSamples = p.integer(value, 1, RT_MAX_SHADOW_SAMPLES);
            if (key == "reference-aa") c.referenceAa = p.integer(value, 1, 16);
            if (key == "cl-options") {
                if (value.empty()) p.fail("cl-options: expected compiler options, got nothing");
                c.clOptions = value;
            }
        } else if (groupNames.empty()) {
            applyGroupKey(defaults, key, value, p);
            if (key == "repeats") c.repeats = defaults.repeats;
            if (key == "warmup") c.warmup = defaults.warmup;
            if (key == "count-rays") c.countRays = defaults.countRays == 1;
        } else {
            // Validate now (for the line number), apply over the defaults below.
            SweepGroup scratch;
            applyGroupKey(scratch, key, value, p);
            groupKeys.back().emplace_back(key, value + "\n" + std::to_string(n));
        }
    }
    if (groupNames.empty())
        throw Error(path.string() + ": no [group] (see bench/sweeps/README.md)");
    for (size_t i = 0; i < groupNames.size(); ++i) {
        SweepGroup g = defaults;
        g.name = groupNames[i];
        for (const auto& [key, valueAndLine] : groupKeys[i]) {
            size_t nl = valueAndLine.rfind('\n');
            ValueParser p(path.string() + ":" + valueAndLine.substr(nl + 1));
            applyGroupKey(g, key, valueAndLine.substr(0, nl), p);
        }
        if (g.scenes.empty()) throw Error(path.string() + ": [" + g.name + "] lists no scenes");
        if (g.pipelines.empty()) g.pipelines = pipelineRegistry().names(true);
        c.groups.push_back(g);
    }
    return c;
}

SweepConfig loadSweep(const fs::path& path) {
    std::ifstream f(path);
    if (!f) throw Error(path.string() + ": cannot read the sweep file");
    std::stringstream ss;
    ss << f.rdbuf();
    return parseSweep(ss.str(), path);
}

fs::path findSweep(const std::string& nameOrPath) {
    fs::path p(nameOrPath);
    if (fs::is_regular_file(p)) return p;
    for (fs::path dir : {fs::path("bench/sweeps"), fs::path(RTLAB_SOURCE_DIR) / "bench/sweeps"})
        if (fs::is_regular_file(dir / p)) return dir / p;
    std::string names;
    for (const auto& [name, what] : listSweeps()) names += (names.empty() ? "" : ", ") + name;
    throw Error(nameOrPath + ": no such sweep file (give a path, or one of " + names + ")");
}

std::vector<std::pair<std::string, std::string>> listSweeps() {
    fs::path dir = fs::is_directory("bench/sweeps") ? fs::path("bench/sweeps")
                                                    : fs::path(RTLAB_SOURCE_DIR) / "bench/sweeps";
    std::vector<std::pair<std::string, std::string>> out;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(dir, ec)) {
        if (!entry.is_regular_file() || entry.path().has_extension()) continue;  // README.md
        // The header comment's first sentence, without "# name — ".
        std::ifstream f(entry.path());
        std::string what;
        for (std::string line; std::getline(f, line) && line.rfind("#", 0) == 0;)
            what += (what.empty() ? "" : " ") + line.substr(line.find_first_not_of("# "));
        if (size_t dash = what.find(" — "); dash != std::string::npos)
            what = what.substr(dash + std::string(" — ").size());
        if (size_t stop = what.find(". "); stop != std::string::npos) what = what.substr(0, stop);
        if (what.size() > 96) what = what.substr(0, what.rfind(' ', 93)) + " ...";
        out.emplace_back(entry.path().filename().string(), what);
    }
    std::sort(out.begin(), out.end());
    return out;
}

std::string Cell::settingKey() const {
    const RenderOptions& o = options;
    std::ostringstream k;
    k << scene << '|' << o.width << 'x' << o.height << '|' << o.bounces << '|' << o.shadowSamples
      << '|' << o.aa << '|' << (accelApplies ? accelName(o.accel) : "-") << '|' << o.memoryBudget
      << '|' << o.adaptiveAa;
    if (o.maxLaunchMs > 0) k << "|L" << o.maxLaunchMs;  // absent before max-launch-ms existed
    k << pipelineOptionsKey(o.pipelineOptions);
    return k.str();
}

std::string Cell::batchKey() const {
    const RenderOptions& o = options;
    std::ostringstream k;
    k << scene << '|' << o.bounces << '|' << o.shadowSamples << '|' << o.aa << '|' << o.memoryBudget
      << '|' << o.adaptiveAa << '|' << repeats << '|' << warmup << '|' << countRays << '|' << images
      << '|' << o.maxLaunchMs << pipelineOptionsKey(o.pipelineOptions);
    // A cell that may be skipped depends on the smaller sizes' outcome: one size per batch.
    if (stopAfterFailure) k << '|' << o.width << 'x' << o.height;
    return k.str();
}

std::string Cell::key() const { return std::string(pipeline) + '|' + settingKey(); }

std::string currentCellKey(const std::string& recordedKey) {
    std::vector<std::string> f;
    for (size_t at = 0;;) {
        size_t bar = recordedKey.find('|', at);
        f.push_back(recordedKey.substr(at, bar - at));
        if (bar == std::string::npos) break;
        at = bar + 1;
    }
    // The old form: pipeline|scene|WxH|B|S|AA|accel|layout|budget|adaptive, then "L<ms>" and
    // option tags. Today's has the adaptive flag at index 8 and after it only fields that
    // begin with a letter, so a bare flag at 9 (and the layout's 0 or 1 at 7) tells them apart.
    auto flag = [](const std::string& x) { return x == "0" || x == "1"; };
    if (f.size() < 10 || !flag(f[7]) || !flag(f[9])) return recordedKey;
    const std::vector<const PipelineOption*> options = pipelineRegistry().options();
    auto layoutAt = std::find_if(options.begin(), options.end(),
                                 [](const PipelineOption* o) { return o->sweepKey == "layout"; });
    if (layoutAt == options.end()) return recordedKey;
    const PipelineOption& layout = **layoutAt;
    const std::string value = layout.choices.at(size_t(std::stoi(f[7])));
    f.erase(f.begin() + 7);
    if (value != layout.text(layout.defaultValue)) {
        // After the launch cap and the tags of options registered before the layout's.
        size_t at = 9;
        if (at < f.size() && f[at].size() > 1 && f[at][0] == 'L' &&
            (std::isdigit((unsigned char)f[at][1]) || f[at][1] == '.'))
            ++at;
        auto before = [&](const std::string& field) {
            for (auto o = options.begin(); o != layoutAt; ++o)
                if (field.rfind((*o)->cellTag, 0) == 0) return true;
            return false;
        };
        while (at < f.size() && before(f[at])) ++at;
        f.insert(f.begin() + std::ptrdiff_t(at), layout.cellTag + value);
    }
    std::string out = f[0];
    for (size_t i = 1; i < f.size(); ++i) out += "|" + f[i];
    return out;
}

std::string Cell::label() const {
    const RenderOptions& o = options;
    std::ostringstream l;
    l << scene << ' ' << pipeline << ' ' << o.width << 'x' << o.height << " b" << o.bounces << " s"
      << o.shadowSamples << " aa" << o.aa;
    if (accelApplies) l << ' ' << accelName(o.accel);
    if (o.adaptiveAa) l << " adaptive";
    for (const PipelineOption* opt : pipelineRegistry().options()) {
        if (!opt->isDefault(o.pipelineOptions)) l << ' ' << opt->describe(o.pipelineOptions);
    }
    if (o.memoryBudget)
        l << " budget "
          << (o.memoryBudget % (1 << 20) ? std::to_string(o.memoryBudget >> 10) + "K"
                                         : std::to_string(o.memoryBudget >> 20) + "M");
    return l.str();
}

std::vector<Cell> expandCells(const SweepConfig& config,
                              const std::function<const Scene&(const std::string&)>& sceneFor) {
    std::vector<Cell> cells;
    std::map<std::string, size_t> index;
    for (size_t gi = 0; gi < config.groups.size(); ++gi) {
        const SweepGroup& g = config.groups[gi];
        for (const std::string& name : g.scenes) {
            const Scene& scene = sceneFor(name);
            const RenderOptions& d = scene.defaults;
            auto orDefault = [](const std::vector<int>& v, int def) {
                return v.empty() ? std::vector<int>{def} : v;
            };
            auto sizes =
                g.sizes.empty() ? std::vector<std::pair<int, int>>{{d.width, d.height}} : g.sizes;
            auto accels = g.accels.empty() ? std::vector<RenderOptions::Accel>{d.accel} : g.accels;
            // The grid and the BVH hold spheres and triangles, bv bounds meshes; a scene of
            // planes alone runs the same program whatever the accel.
            bool prims = !scene.spheres.empty() || !scene.triangles.empty();
            if (!prims) accels = {d.accel};
            // Pipelines innermost: the pipelines of a setting run back to back, so slow
            // drift of the machine (clocks, other load) hits both sides of a ratio alike.
            for (auto [w, h] : sizes)
                for (int b : orDefault(g.bounces, d.bounces))
                    for (int s : orDefault(g.shadowSamples, d.shadowSamples))
                        for (int a : orDefault(g.aa, d.aa))
                            for (RenderOptions::Accel accel : accels)
                                for (std::string pipeline : g.pipelines) {
                                    Cell c;
                                    c.scene = name;
                                    c.pipeline = pipeline;
                                    c.options = d;
                                    c.options.width = w;
                                    c.options.height = h;
                                    c.options.bounces = b;
                                    c.options.shadowSamples = s;
                                    c.options.aa = a;
                                    c.options.accel = accel;
                                    c.options.memoryBudget = g.memoryBudget;
                                    c.options.adaptiveAa = g.adaptive;
                                    c.options.maxLaunchMs = g.maxLaunchMs;
                                    c.options.pipelineOptions = g.pipelineOptions;
                                    c.accelApplies = prims;
                                    c.branching = scene.branching();
                                    c.groups = {g.name};
                                    c.groupIds = {int(gi)};
                                    c.stopAfterFailure = g.stopAfterFailure;
                                    c.maxFrameS = g.maxFrameS;
                                    c.images = g.images;
                                    c.repeats = g.repeats > 0 ? g.repeats : config.repeats;
                                    c.warmup = g.warmup >= 0 ? g.warmup : config.warmup;
                                    c.countRays =
                                        g.countRays >= 0 ? g.countRays == 1 : config.countRays;
                                    auto [it, fresh] = index.emplace(c.key(), cells.size());
                                    if (fresh) {
                                        cells.push_back(c);
                                        continue;
                                    }
                                    Cell& old = cells[it->second];
                                    if (std::find(old.groups.begin(), old.groups.end(), g.name) ==
                                        old.groups.end())
                                        old.groups.push_back(g.name);
                                    old.groupIds.push_back(int(gi));
                                    old.stopAfterFailure =
                                        old.stopAfterFailure || g.stopAfterFailure;
                                    if (g.maxFrameS > 0)
                                        old.maxFrameS = old.maxFrameS > 0
                                                            ? std::min(old.maxFrameS, g.maxFrameS)
                                                            : g.maxFrameS;
                                    old.images = old.images || g.images;
                                    old.repeats = std::max(old.repeats, c.repeats);
                                    old.warmup = std::max(old.warmup, c.warmup);
                                    old.countRays = old.countRays || c.countRays;
                                }
        }
    }
    return cells;
}

std::string skipReason(const SweepConfig& config, const Cell& cell,
                       const std::vector<Stop>& stops) {
    // Every setting but size and bounce limit must match: the same key with those blanked.
    auto others = [](const Cell& c) {
        Cell o = c;
        o.options.width = o.options.height = 0;
        o.options.bounces = 0;
        return o.key();
    };
    const std::string mine = others(cell);
    for (const Stop& s : stops) {
        const RenderOptions &a = s.cell.options, &b = cell.options;
        if (s.cell.key() == cell.key() || others(s.cell) != mine) continue;
        if (b.width < a.width || b.height < a.height || b.bounces < a.bounces) continue;
        bool shared = false;
        for (int g : s.cell.groupIds)
            if (g >= 0 && size_t(g) < config.groups.size() &&
                config.groups[size_t(g)].stopAfterFailure &&
                std::find(cell.groupIds.begin(), cell.groupIds.end(), g) != cell.groupIds.end())
                shared = true;
        if (!shared) continue;
        std::ostringstream why;
        why << cell.pipeline << " stopped at " << a.width << 'x' << a.height << " B=" << a.bounces
            << " (" << s.why << "); this setting is no smaller";
        return why.str();
    }
    return "";
}

std::vector<std::string> sweepScenes(const SweepConfig& config) {
    std::vector<std::string> out;
    for (const SweepGroup& g : config.groups)
        for (const std::string& s : g.scenes)
            if (std::find(out.begin(), out.end(), s) == out.end()) out.push_back(s);
    return out;
}

}  // namespace rt::bench
