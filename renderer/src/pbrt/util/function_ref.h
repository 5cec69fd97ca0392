// A non-owning reference to a callable, for parameters that are called but not kept.
//
// Written here because C++17 has none (std::function_ref is C++26): std::function, which
// the renderer used before, is built and destroyed at every surface hit (its manager showed
// as 1.8% of a render's time); this is two pointers and an indirect call.
#pragma once

#include <memory>
#include <type_traits>
#include <utility>

namespace pbrt {

template <typename Signature>
class FunctionRef;

template <typename R, typename... Args>
class FunctionRef<R(Args...)> {
  public:
    // Refers to f, which must outlive every call (a lambda passed as an argument does).
    template <typename F, typename = std::enable_if_t<!std::is_same_v<std::decay_t<F>, FunctionRef> &&
                                                      std::is_invocable_r_v<R, F &, Args...>>>
    FunctionRef(F &&f)
        : object(const_cast<void *>(static_cast<const void *>(std::addressof(f)))),
          call([](void *o, Args... args) -> R {
              return (*static_cast<std::remove_reference_t<F> *>(o))(std::forward<Args>(args)...);
          }) {}

    R operator()(Args... args) const { return call(object, std::forward<Args>(args)...); }

  private:
    void *object;
    R (*call)(void *, Args...);
};

}  // namespace pbrt
