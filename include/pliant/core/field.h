// SPDX-License-Identifier: MIT
// SPDX-FileCopyrightText: 2026 pliant contributors
#pragma once

/// \file
/// `Field<T>`: one scalar per grid node, as one contiguous row-major plane with a ghost ring
/// (docs/style.md §6). Positions are three planes (`Vec3Field`), displacement and velocity one
/// each.
///
/// Layout: the padded plane has `stride() = nx + 2g` columns and `ny + 2g` rows; node (x, y),
/// -g <= x < nx + g, lives at `origin()[y * stride() + x]`. Ghosts are valid only after
/// `fill_ghosts`; twins are kept equal to their canonical node by `sync_twins`.

#include <pliant/core/tetra_grid.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <span>
#include <vector>

namespace pliant::core
{

template <typename T>
class Field
{
public:
    Field() = default;
    /// A field over `grid` with a ghost ring of `ghost` (0..k_max_ghost) nodes, all set to `value`.
    explicit Field(const TetraGrid& grid, int ghost = 0, T value = T{})
        : level_(grid.level()),
          nx_(grid.nx()),
          ny_(grid.ny()),
          ghost_(ghost),
          stride_(grid.nx() + 2 * ghost)
    {
        PLIANT_ASSERT(ghost >= 0 && ghost <= k_max_ghost, "Field: ghost width out of range");
        data_.assign(static_cast<std::size_t>(stride_) * static_cast<std::size_t>(ny_ + 2 * ghost),
                     value);
    }

    [[nodiscard]] int level() const noexcept { return level_; }
    [[nodiscard]] int nx() const noexcept { return nx_; }
    [[nodiscard]] int ny() const noexcept { return ny_; }
    [[nodiscard]] int ghost() const noexcept { return ghost_; }
    [[nodiscard]] std::ptrdiff_t stride() const noexcept { return stride_; }
    [[nodiscard]] bool empty() const noexcept { return data_.empty(); }

    /// Offset of node (x, y) from `origin()`.
    [[nodiscard]] std::ptrdiff_t offset(int x, int y) const noexcept
    {
        return static_cast<std::ptrdiff_t>(y) * stride_ + x;
    }
    /// Offset of node (x, y) in the padded plane (`data()`), as used by `GhostCopy`.
    [[nodiscard]] std::ptrdiff_t padded_offset(int x, int y) const noexcept
    {
        return static_cast<std::ptrdiff_t>(y + ghost_) * stride_ + (x + ghost_);
    }
    [[nodiscard]] T& at(int x, int y) noexcept
    {
        PLIANT_DEBUG_ASSERT(x >= -ghost_ && x < nx_ + ghost_ && y >= -ghost_ && y < ny_ + ghost_,
                            "Field::at out of the padded plane");
        return data_[static_cast<std::size_t>(padded_offset(x, y))];
    }
    [[nodiscard]] const T& at(int x, int y) const noexcept
    {
        PLIANT_DEBUG_ASSERT(x >= -ghost_ && x < nx_ + ghost_ && y >= -ghost_ && y < ny_ + ghost_,
                            "Field::at out of the padded plane");
        return data_[static_cast<std::size_t>(padded_offset(x, y))];
    }
    /// Value at a node index (in range, no ghosts).
    [[nodiscard]] T& operator[](NodeIndex n) noexcept
    {
        return at(static_cast<int>(n.value) % nx_, static_cast<int>(n.value) / nx_);
    }
    [[nodiscard]] const T& operator[](NodeIndex n) const noexcept
    {
        return at(static_cast<int>(n.value) % nx_, static_cast<int>(n.value) / nx_);
    }

    /// Pointer to node (0, 0) inside the padded plane.
    [[nodiscard]] T* origin() noexcept { return data_.data() + padded_offset(0, 0); }
    [[nodiscard]] const T* origin() const noexcept { return data_.data() + padded_offset(0, 0); }
    [[nodiscard]] std::span<T> padded() noexcept { return data_; }
    [[nodiscard]] std::span<const T> padded() const noexcept { return data_; }

    void fill(T value) noexcept { std::fill(data_.begin(), data_.end(), value); }

    /// Copies the in-range nodes row by row into `out` (size nx*ny).
    void copy_to(std::span<T> out) const noexcept
    {
        PLIANT_ASSERT(out.size() == static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_),
                      "Field::copy_to: size mismatch");
        for (int y = 0; y < ny_; ++y)
            for (int x = 0; x < nx_; ++x)
                out[static_cast<std::size_t>(y * nx_ + x)] = at(x, y);
    }
    /// Sets the in-range nodes from `in` (size nx*ny), row by row.
    void copy_from(std::span<const T> in) noexcept
    {
        PLIANT_ASSERT(in.size() == static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_),
                      "Field::copy_from: size mismatch");
        for (int y = 0; y < ny_; ++y)
            for (int x = 0; x < nx_; ++x)
                at(x, y) = in[static_cast<std::size_t>(y * nx_ + x)];
    }

    friend bool operator==(const Field&, const Field&) = default;

private:
    int level_ = 0;
    int nx_ = 0;
    int ny_ = 0;
    int ghost_ = 0;
    std::ptrdiff_t stride_ = 0;
    std::vector<T> data_;
};

/// Three planes, one per coordinate (positions, normals).
template <typename T>
using Vec3Field = std::array<Field<T>, 3>;

/// Writes every ghost node from the canonical node it stands for. \pre field made for `grid`.
template <typename T>
void fill_ghosts(const TetraGrid& grid, Field<T>& field) noexcept
{
    PLIANT_ASSERT(field.level() == grid.level(), "fill_ghosts: field of another level");
    if (field.ghost() == 0)
        return;
    T* data = field.padded().data();
    for (const GhostCopy& g : grid.ghost_table(field.ghost()))
        data[g.dst] = data[g.src];
}

/// Writes every twin node from its canonical node, so twins stay equal (docs/design.md §1).
template <typename T>
void sync_twins(const TetraGrid& grid, Field<T>& field) noexcept
{
    PLIANT_ASSERT(field.level() == grid.level(), "sync_twins: field of another level");
    for (const TwinPair& t : grid.twins())
        field[t.twin] = field[t.canonical];
}

/// Largest difference between a twin and its canonical node (0 for a consistent field).
template <typename T>
[[nodiscard]] T max_twin_mismatch(const TetraGrid& grid, const Field<T>& field) noexcept
{
    T worst{};
    for (const TwinPair& t : grid.twins())
    {
        const T d = field[t.twin] > field[t.canonical] ? field[t.twin] - field[t.canonical]
                                                       : field[t.canonical] - field[t.twin];
        worst = d > worst ? d : worst;
    }
    return worst;
}

}  // namespace pliant::core
