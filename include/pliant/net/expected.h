// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// `Expected<T, E>`: a value or a small error enum, for the codec's hot path (docs/style.md §5,
/// kind 3: hostile bytes are never asserted on or thrown for). `core::Result` carries a message
/// string, which a decoder that rejects a datagram per packet must not build; this type carries
/// only the enum. Member names follow C++23 `std::expected`.

#include <pliant/core/assert.h>

#include <utility>
#include <variant>

namespace pliant::net
{

/// Wraps an error so that `return Unexpected{DecodeError::BadLength}` reads like `std::unexpected`.
template <typename E>
struct Unexpected
{
    E error;
};
template <typename E>
Unexpected(E) -> Unexpected<E>;

template <typename T, typename E>
class [[nodiscard]] Expected
{
public:
    Expected(T value)
        : v_(std::in_place_index<0>, std::move(value)) {}               // NOLINT implicit by design
    Expected(Unexpected<E> e) : v_(std::in_place_index<1>, e.error) {}  // NOLINT

    [[nodiscard]] bool has_value() const noexcept { return v_.index() == 0; }
    explicit operator bool() const noexcept { return has_value(); }

    [[nodiscard]] T& value() &
    {
        PLIANT_ASSERT(has_value(), "Expected::value() on an error");
        return *std::get_if<0>(&v_);
    }
    [[nodiscard]] const T& value() const&
    {
        PLIANT_ASSERT(has_value(), "Expected::value() on an error");
        return *std::get_if<0>(&v_);
    }
    [[nodiscard]] T&& value() &&
    {
        PLIANT_ASSERT(has_value(), "Expected::value() on an error");
        return std::move(*std::get_if<0>(&v_));
    }
    T& operator*() & { return value(); }
    const T& operator*() const& { return value(); }
    T* operator->() { return &value(); }
    const T* operator->() const { return &value(); }

    [[nodiscard]] E error() const
    {
        PLIANT_ASSERT(!has_value(), "Expected::error() on a value");
        return *std::get_if<1>(&v_);
    }

private:
    std::variant<T, E> v_;
};

}  // namespace pliant::net
