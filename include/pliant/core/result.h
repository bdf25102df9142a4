// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// `Result<T>`: a value or an `Error`, the return type of every function that reads outside input
/// (docs/style.md §5). A small stand-in for C++23 `std::expected`, with the same member names so
/// the switch is mechanical once the toolchain has it.

#include <pliant/core/assert.h>
#include <pliant/core/error.h>

#include <string>
#include <utility>
#include <variant>

namespace pliant::core
{

/// Wraps an error so that `return unexpected(...)` reads like `std::unexpected`.
struct Unexpected
{
    Error error;
};

/// Makes an error result: `return fail(ErrorCode::OpenBoundary, "validate: ...");`
[[nodiscard]] inline Unexpected fail(ErrorCode code, std::string message)
{
    return Unexpected{Error{code, std::move(message)}};
}

/// A Result's value read while it holds `error`: a contract failure (the assert handler, then
/// abort) whose message carries the error's code and message, so that the reason the call
/// failed is not lost.
[[noreturn]] void value_of_error(const Error& error, const char* file, int line);

template <typename T>
class [[nodiscard]] Result
{
public:
    Result(T value) : v_(std::in_place_index<0>, std::move(value)) {}  // NOLINT implicit by design
    Result(Unexpected e) : v_(std::in_place_index<1>, std::move(e.error)) {}  // NOLINT
    Result(Error e) : v_(std::in_place_index<1>, std::move(e)) {}             // NOLINT

    [[nodiscard]] bool has_value() const noexcept { return v_.index() == 0; }
    explicit operator bool() const noexcept { return has_value(); }

    [[nodiscard]] T& value() &
    {
#if !defined(PLIANT_DISABLE_ASSERT)
        if (!has_value()) [[unlikely]]
            value_of_error(std::get<1>(v_), __FILE__, __LINE__);
#endif
        return std::get<0>(v_);
    }
    [[nodiscard]] const T& value() const&
    {
#if !defined(PLIANT_DISABLE_ASSERT)
        if (!has_value()) [[unlikely]]
            value_of_error(std::get<1>(v_), __FILE__, __LINE__);
#endif
        return std::get<0>(v_);
    }
    [[nodiscard]] T&& value() &&
    {
#if !defined(PLIANT_DISABLE_ASSERT)
        if (!has_value()) [[unlikely]]
            value_of_error(std::get<1>(v_), __FILE__, __LINE__);
#endif
        return std::get<0>(std::move(v_));
    }
    T& operator*() &
    {
        return value();
    }
    const T& operator*() const&
    {
        return value();
    }
    T&& operator*() &&
    {
        return std::move(*this).value();
    }
    T* operator->()
    {
        return &value();
    }
    const T* operator->() const
    {
        return &value();
    }

    [[nodiscard]] const Error& error() const
    {
        PLIANT_ASSERT(!has_value(), "Result::error() on a value");
        return std::get<1>(v_);
    }

private:
    std::variant<T, Error> v_;
};

/// A result with no value: success or an error.
template <>
class [[nodiscard]] Result<void>
{
public:
    Result() = default;
    Result(Unexpected e) : error_(std::move(e.error)), ok_(false) {}  // NOLINT
    Result(Error e) : error_(std::move(e)), ok_(false) {}             // NOLINT

    [[nodiscard]] bool has_value() const noexcept { return ok_; }
    explicit operator bool() const noexcept { return ok_; }
    [[nodiscard]] const Error& error() const
    {
        PLIANT_ASSERT(!ok_, "Result::error() on a value");
        return error_;
    }

private:
    Error error_{};
    bool ok_ = true;
};

}  // namespace pliant::core
