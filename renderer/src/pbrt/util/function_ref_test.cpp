#include <pbrt/util/function_ref.h>

#include <gtest/gtest.h>

#include <functional>
#include <string>

using namespace pbrt;

namespace {
int CallTwice(FunctionRef<int(int)> f, int x) { return f(f(x)); }
}  // namespace

TEST(FunctionRef, CallsTheCallableItRefersTo) {
    EXPECT_EQ(CallTwice([](int x) { return 3 * x + 1; }, 2), 22);
    // A reference, not a copy: state the callable changes is the caller's.
    int calls = 0;
    auto counting = [&calls](int x) { ++calls; return x; };
    EXPECT_EQ(CallTwice(counting, 5), 5);
    EXPECT_EQ(calls, 2);
    // A mutable lambda's own state lives on in the lambda referred to.
    auto next = [n = 0](int) mutable { return ++n; };
    FunctionRef<int(int)> r = next;
    r(0);
    r(0);
    EXPECT_EQ(next(0), 3);
}

TEST(FunctionRef, TakesStdFunctionsAndFunctionPointers) {
    std::function<std::string(const std::string &)> twice = [](const std::string &s) { return s + s; };
    FunctionRef<std::string(const std::string &)> r = twice;
    EXPECT_EQ(r("ab"), "abab");
    struct Free {
        static float Half(float x) { return x / 2; }
    };
    float (*half)(float) = Free::Half;  // a function pointer (an object) works too
    FunctionRef<float(float)> h = half;
    EXPECT_EQ(h(3), 1.5f);
}
