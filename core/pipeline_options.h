// rtlab — options a pipeline declares for itself, in its registry entry (PipelineInfo::options):
// name, type, default, allowed values, help, sweep-file key, and how a value shows in sweep cells
// and rows. Front ends make their flags, sweep keys, cell keys, labels and row fields from these
// declarations; the core carries the values (RenderOptions::pipelineOptions) without knowing any
// option by name, and each pipeline reads its own back, typed, through its declarations.
#pragma once

#include <map>
#include <string>
#include <variant>
#include <vector>

namespace rt {

// A value of a pipeline option: a whole number (Integer) or one of its names (Choice).
using OptionValue = std::variant<long long, std::string>;

// The values set for pipeline options, by option name. An option that is not set has its
// declared default, so a RenderOptions made without any front end still renders as declared.
class PipelineOptionValues {
  public:
    void set(const std::string& name, OptionValue value) { values_[name] = std::move(value); }
    void reset(const std::string& name) { values_.erase(name); }
    // Sets every value `other` holds, over the ones held here.
    void setAll(const PipelineOptionValues& other) {
        for (const auto& [name, value] : other.values_) values_[name] = value;
    }
    const OptionValue* find(const std::string& name) const {
        auto it = values_.find(name);
        return it == values_.end() ? nullptr : &it->second;
    }
    bool operator==(const PipelineOptionValues&) const = default;

  private:
    std::map<std::string, OptionValue> values_;
};

// A setting of a pipeline's own options that tests and the smoke check cover one by one.
struct PipelineVariant {
    std::string name;             // "weighted"; "" for the defaults of a pipeline without variants
    PipelineOptionValues values;  // the options it sets; the others keep their defaults
};

struct PipelineOption {
    enum class Type { Integer, Choice };
    // The key of PipelineOptionValues; the command-line flag is "--" + name.
    std::string name = {};
    Type type = Type::Choice;
    std::string help = {};  // the flag's --help text, its default said in it
    OptionValue defaultValue = {};
    // Choice: the names allowed, in the order of the pipeline's enum (see index()).
    std::vector<std::string> choices = {};
    // Integer: the range a value given must lie in; the default may lie outside it (0 for
    // "chosen by the pipeline"), and the sweep-file value "default" stands for it.
    long long min = 0, max = 0;
    std::string sweepKey = {};  // the key in sweep files (bench/sweeps/README.md); usually the name
    // Sweep cells: a value other than the default adds "|" + cellTag + value to the cell's key
    // (the rows' "cell", which resumed sweeps match) and `label`, "{}" replaced by the value, to
    // the cell's label. Tags are one letter and unique over the registry.
    std::string cellTag = {};
    std::string label = {};

    std::string flag() const { return "--" + name; }
    // The field of result rows and --stats-json that holds the value: the sweep key with '_'
    // for '-' ("queue_launch").
    std::string field() const;
    // The value in `values`, or the default.
    const OptionValue& value(const PipelineOptionValues& values) const;
    long long integer(const PipelineOptionValues& values) const;
    const std::string& choice(const PipelineOptionValues& values) const;
    // Choice: the position of the value in `choices`, for the pipeline's enum.
    size_t index(const PipelineOptionValues& values) const;
    bool isDefault(const PipelineOptionValues& values) const;
    // "4096", "device".
    std::string text(const OptionValue& value) const;
    // `label` with the value in `values` in it: "256 lanes a group", "nested loop".
    std::string describe(const PipelineOptionValues& values) const;

    // Checks a value and stores it; throws rt::Error naming the flag:
    // "--pool 0: must be in 1..67108864", "--queue-launch up: must be readback or device".
    void set(PipelineOptionValues& values, OptionValue value) const;
    // Choice: the position of `name` in `choices`; throws as set() does.
    size_t indexOf(const std::string& name) const;
};

// "a", "a or b", "a, b or c": the choices as error messages say them.
std::string choiceList(const std::vector<std::string>& choices);

}  // namespace rt
