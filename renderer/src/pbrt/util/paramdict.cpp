#include <pbrt/util/paramdict.h>

namespace pbrt {

namespace {

std::string Describe(const ParsedParameter &p) { return "\"" + p.type + " " + p.name + "\""; }

// The number of values a parameter holds, whatever its type.
size_t ValueCount(const ParsedParameter &p) {
    return p.floats.size() + p.ints.size() + p.strings.size() + p.bools.size();
}

void RequireOne(const ParsedParameter &p) {
    if (ValueCount(p) != 1)
        throw PbrtError(p.loc, "parameter " + Describe(p) + " expects one value, got " +
                                   std::to_string(ValueCount(p)));
}

}  // namespace

ParameterDictionary::ParameterDictionary(ParsedParameterVector params) : params(std::move(params)) {}

const ParsedParameter *ParameterDictionary::Lookup(const std::string &name) const {
    for (const ParsedParameter &p : params)
        if (p.name == name) return &p;
    return nullptr;
}

const ParsedParameter *ParameterDictionary::LookupTyped(const std::string &name,
                                                        const char *type) const {
    const ParsedParameter *p = Lookup(name);
    if (!p) return nullptr;
    if (p->type != type)
        throw PbrtError(p->loc, "parameter " + Describe(*p) + " has type \"" + p->type +
                                    "\", expected \"" + type + "\"");
    p->lookedUp = true;
    return p;
}

Float ParameterDictionary::GetOneFloat(const std::string &name, Float def) const {
    const ParsedParameter *p = LookupTyped(name, "float");
    if (!p) return def;
    RequireOne(*p);
    return Float(p->floats[0]);
}

int ParameterDictionary::GetOneInt(const std::string &name, int def) const {
    const ParsedParameter *p = LookupTyped(name, "integer");
    if (!p) return def;
    RequireOne(*p);
    return p->ints[0];
}

bool ParameterDictionary::GetOneBool(const std::string &name, bool def) const {
    const ParsedParameter *p = LookupTyped(name, "bool");
    if (!p) return def;
    RequireOne(*p);
    return p->bools[0] != 0;
}

std::string ParameterDictionary::GetOneString(const std::string &name,
                                              const std::string &def) const {
    const ParsedParameter *p = LookupTyped(name, "string");
    if (!p) return def;
    RequireOne(*p);
    return p->strings[0];
}

std::array<Float, 3> ParameterDictionary::GetOnePoint3(const std::string &name,
                                                       std::array<Float, 3> def) const {
    return GetOneTuple3(name, "point3", def);
}

std::array<Float, 3> ParameterDictionary::GetOneVector3(const std::string &name,
                                                        std::array<Float, 3> def) const {
    return GetOneTuple3(name, "vector3", def);
}

std::array<Float, 3> ParameterDictionary::GetOneTuple3(const std::string &name, const char *type,
                                                       std::array<Float, 3> def) const {
    const ParsedParameter *p = LookupTyped(name, type);
    if (!p) return def;
    if (p->floats.size() != 3)
        throw PbrtError(p->loc, "parameter " + Describe(*p) + " expects 3 values, got " +
                                    std::to_string(p->floats.size()));
    return {Float(p->floats[0]), Float(p->floats[1]), Float(p->floats[2])};
}

std::vector<Float> ParameterDictionary::GetFloatArray(const std::string &name) const {
    const ParsedParameter *p = LookupTyped(name, "float");
    if (!p) return {};
    return std::vector<Float>(p->floats.begin(), p->floats.end());
}

std::vector<int> ParameterDictionary::GetIntArray(const std::string &name) const {
    const ParsedParameter *p = LookupTyped(name, "integer");
    return p ? p->ints : std::vector<int>{};
}

std::vector<std::string> ParameterDictionary::GetStringArray(const std::string &name) const {
    const ParsedParameter *p = LookupTyped(name, "string");
    return p ? p->strings : std::vector<std::string>{};
}

template <int N>
std::vector<std::array<Float, N>> ParameterDictionary::GetTuples(const std::string &name,
                                                                 const char *type) const {
    const ParsedParameter *p = LookupTyped(name, type);
    if (!p) return {};
    if (p->floats.size() % N != 0)
        throw PbrtError(p->loc, "parameter " + Describe(*p) + " expects a multiple of " +
                                    std::to_string(N) + " values, got " +
                                    std::to_string(p->floats.size()));
    std::vector<std::array<Float, N>> out(p->floats.size() / N);
    for (size_t i = 0; i < out.size(); ++i)
        for (int c = 0; c < N; ++c) out[i][c] = Float(p->floats[N * i + c]);
    return out;
}

std::vector<std::array<Float, 2>> ParameterDictionary::GetPoint2Array(
    const std::string &name) const {
    return GetTuples<2>(name, "point2");
}
std::vector<std::array<Float, 3>> ParameterDictionary::GetPoint3Array(
    const std::string &name) const {
    return GetTuples<3>(name, "point3");
}
std::vector<std::array<Float, 3>> ParameterDictionary::GetVector3Array(
    const std::string &name) const {
    return GetTuples<3>(name, "vector3");
}
std::vector<std::array<Float, 3>> ParameterDictionary::GetNormal3Array(
    const std::string &name) const {
    return GetTuples<3>(name, "normal3");
}

std::optional<std::array<Float, 3>> ParameterDictionary::GetOneRGB(const std::string &name) const {
    const ParsedParameter *p = Lookup(name);
    if (!p || p->type != "rgb") return std::nullopt;
    p->lookedUp = true;
    if (p->floats.size() != 3)
        throw PbrtError(p->loc, "parameter " + Describe(*p) + " expects 3 values, got " +
                                    std::to_string(p->floats.size()));
    return std::array<Float, 3>{Float(p->floats[0]), Float(p->floats[1]), Float(p->floats[2])};
}

std::string ParameterDictionary::GetTexture(const std::string &name) const {
    const ParsedParameter *p = Lookup(name);
    if (!p || p->type != "texture") return "";
    p->lookedUp = true;
    RequireOne(*p);
    return p->strings[0];
}

const ParsedParameter *ParameterDictionary::Find(const std::string &name) const {
    const ParsedParameter *p = Lookup(name);
    if (p) p->lookedUp = true;
    return p;
}

FileLoc ParameterDictionary::Loc(const std::string &name) const {
    const ParsedParameter *p = Lookup(name);
    return p ? p->loc : FileLoc{};
}

std::vector<const ParsedParameter *> ParameterDictionary::Unused() const {
    std::vector<const ParsedParameter *> unused;
    // A parameter shadowed by an earlier one of the same name counts as used when that one was.
    for (const ParsedParameter &p : params) {
        if (p.lookedUp) continue;
        bool shadowUsed = false;
        for (const ParsedParameter &q : params)
            if (&q != &p && q.lookedUp && q.name == p.name) shadowUsed = true;
        if (!shadowUsed) unused.push_back(&p);
    }
    return unused;
}

}  // namespace pbrt
