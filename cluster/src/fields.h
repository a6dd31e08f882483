// How many members an aggregate has, at compile time: the largest N for which T{a1, ..., aN}
// compiles with arguments that convert to anything. The wire writers static_assert it next to
// each struct they write, so that a member added to a scene struct without being written,
// read and mapped fails the build there (issue 17: a missed field already shipped a bug).
//
// Each argument converts to the member's own type, so a member that is itself an aggregate
// (Float3, Transform, std::array, TextureDesc) takes one argument, not its members (no brace
// elision). Checked with GCC 12 and clang 14 on every struct the protocol writes, default member
// initialisers, std::string, std::vector and std::optional members included (the tests in
// tests/cluster/scene_state_test.cpp count them).
#pragma once

#include <cstddef>
#include <utility>

namespace rtwall::cluster {

namespace detail {

struct AnyMember {
    template <class T> operator T() const;  // declared only: used in unevaluated requires-expressions
};

template <class T, size_t... I> constexpr bool bracesTake(std::index_sequence<I...>) {
    return requires { T{(void(I), AnyMember{})...}; };
}

}  // namespace detail

template <class T, size_t N = 0> constexpr size_t fieldCount() {
    if constexpr (detail::bracesTake<T>(std::make_index_sequence<N + 1>{})) return fieldCount<T, N + 1>();
    else return N;
}

}  // namespace rtwall::cluster
