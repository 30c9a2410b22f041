// rtlab — reading, checking and printing the values of declared pipeline options (see
// pipeline_options.h).
#include "core/pipeline_options.h"

#include <algorithm>

#include "core/error.h"

namespace rt {

const OptionValue& PipelineOption::value(const PipelineOptionValues& values) const {
    const OptionValue* v = values.find(name);
    return v ? *v : defaultValue;
}

std::string PipelineOption::field() const {
    std::string f = sweepKey;
    std::replace(f.begin(), f.end(), '-', '_');
    return f;
}

long long PipelineOption::integer(const PipelineOptionValues& values) const {
    const long long* v = std::get_if<long long>(&value(values));
    if (!v) throw Error("pipeline option " + name + " is not a number (internal error)");
    return *v;
}

const std::string& PipelineOption::choice(const PipelineOptionValues& values) const {
    const std::string* v = std::get_if<std::string>(&value(values));
    if (!v) throw Error("pipeline option " + name + " is not a choice (internal error)");
    return *v;
}

size_t PipelineOption::index(const PipelineOptionValues& values) const {
    return indexOf(choice(values));
}

bool PipelineOption::isDefault(const PipelineOptionValues& values) const {
    return value(values) == defaultValue;
}

std::string PipelineOption::text(const OptionValue& v) const {
    if (const long long* n = std::get_if<long long>(&v)) return std::to_string(*n);
    return std::get<std::string>(v);
}

std::string PipelineOption::describe(const PipelineOptionValues& values) const {
    std::string out = label;
    const size_t at = out.find("{}");
    if (at != std::string::npos) out.replace(at, 2, text(value(values)));
    return out;
}

size_t PipelineOption::indexOf(const std::string& choice) const {
    auto it = std::find(choices.begin(), choices.end(), choice);
    if (it == choices.end())
        throw Error(flag() + " " + choice + ": must be " + choiceList(choices));
    return size_t(it - choices.begin());
}

void PipelineOption::set(PipelineOptionValues& values, OptionValue v) const {
    if (type == Type::Integer) {
        const long long* n = std::get_if<long long>(&v);
        if (!n) throw Error(flag() + " " + text(v) + ": not a whole number");
        if (*n < min || *n > max)
            throw Error(flag() + " " + std::to_string(*n) + ": must be in " + std::to_string(min) +
                        ".." + std::to_string(max));
    } else {
        indexOf(text(v));
        if (!std::holds_alternative<std::string>(v)) v = text(v);
    }
    values.set(name, std::move(v));
}

std::string choiceList(const std::vector<std::string>& choices) {
    std::string out;
    for (size_t i = 0; i < choices.size(); ++i)
        out += (i == 0 ? "" : i + 1 == choices.size() ? " or " : ", ") + choices[i];
    return out;
}

}  // namespace rt
