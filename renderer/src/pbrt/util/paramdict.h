// Typed access to a directive's parameter list. Every getter marks the parameter it finds as
// used, so the scene builder can report parameters that nothing read (Unused()).
#pragma once

#include <pbrt/parser.h>
#include <pbrt/pbrt.h>

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace pbrt {

// Lookup rules:
// - A name may appear more than once (the scene builder appends "Attribute" defaults after a
//   directive's own parameters); the first one wins.
// - The typed getters (GetOneFloat, GetPoint3Array, ...) throw PbrtError with the parameter's
//   FileLoc when the parameter exists with another type, or when a GetOne* parameter does not
//   have exactly one value. A missing parameter gives the default (or an empty array).
// - GetOneRGB and GetTexture are for parameters that may take several types ("reflectance"
//   may be rgb, spectrum or texture): a parameter of another type gives nullopt / "" and is
//   left unmarked. Find gives raw access (spectrum and blackbody values).
class ParameterDictionary {
  public:
    ParameterDictionary() = default;
    explicit ParameterDictionary(ParsedParameterVector params);

    Float GetOneFloat(const std::string &name, Float def) const;
    int GetOneInt(const std::string &name, int def) const;
    bool GetOneBool(const std::string &name, bool def) const;
    std::string GetOneString(const std::string &name, const std::string &def) const;
    std::array<Float, 3> GetOnePoint3(const std::string &name, std::array<Float, 3> def) const;
    std::array<Float, 3> GetOneVector3(const std::string &name, std::array<Float, 3> def) const;

    std::vector<Float> GetFloatArray(const std::string &name) const;
    std::vector<int> GetIntArray(const std::string &name) const;
    std::vector<std::string> GetStringArray(const std::string &name) const;
    std::vector<std::array<Float, 2>> GetPoint2Array(const std::string &name) const;
    std::vector<std::array<Float, 3>> GetPoint3Array(const std::string &name) const;
    std::vector<std::array<Float, 3>> GetVector3Array(const std::string &name) const;
    std::vector<std::array<Float, 3>> GetNormal3Array(const std::string &name) const;

    // The value of an "rgb" parameter; nullopt if absent or of another type.
    std::optional<std::array<Float, 3>> GetOneRGB(const std::string &name) const;
    // The texture name of a "texture" parameter; "" if absent or of another type.
    std::string GetTexture(const std::string &name) const;
    // The first parameter with this name (marked used), or nullptr.
    const ParsedParameter *Find(const std::string &name) const;
    // Where the parameter was written; an empty FileLoc if it is absent.
    FileLoc Loc(const std::string &name) const;

    // Parameters no getter has looked up (nor an earlier one of the same name), in the order
    // written.
    std::vector<const ParsedParameter *> Unused() const;
    const ParsedParameterVector &Parameters() const { return params; }

  private:
    // The first parameter named `name`, without marking it.
    const ParsedParameter *Lookup(const std::string &name) const;
    // The first parameter named `name`, checked to have type `type` and marked; null if absent.
    const ParsedParameter *LookupTyped(const std::string &name, const char *type) const;
    std::array<Float, 3> GetOneTuple3(const std::string &name, const char *type,
                                      std::array<Float, 3> def) const;
    template <int N>
    std::vector<std::array<Float, N>> GetTuples(const std::string &name, const char *type) const;

    ParsedParameterVector params;
};

}  // namespace pbrt
