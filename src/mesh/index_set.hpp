#ifndef DPSM_MESH_INDEX_SET_HPP
#define DPSM_MESH_INDEX_SET_HPP

// A set of cells or faces that a sparse sub-step builds from the lists before
// it ("the owned cells of these faces"), listed in increasing order: in the
// mesh's Hilbert order, so that the passes over the list read memory near
// where they read last. A byte marks each index and a byte each block of
// indices, so that listing reads only the blocks something was added to.
// Adding from several threads at once is safe (relaxed atomic stores of the
// same value); listing empties the set.

#include <cstdint>
#include <cstring>
#include <vector>

namespace dpsm {

class IndexSet {
public:
    // Indices below `bound` may be added.
    void reserve(std::int64_t bound) {
        if (static_cast<std::int64_t>(marks_.size()) >= bound) return;
        const std::size_t blocks = static_cast<std::size_t>(bound >> kShift) + 1;
        marks_.assign(blocks << kShift, 0);
        blocks_.assign(blocks, 0);
    }

    void add(std::int64_t i) {
        std::uint8_t &mark = marks_[static_cast<std::size_t>(i)];
        if (__atomic_load_n(&mark, __ATOMIC_RELAXED)) return;
        __atomic_store_n(&mark, std::uint8_t{1}, __ATOMIC_RELAXED);
        std::uint8_t &block = blocks_[static_cast<std::size_t>(i >> kShift)];
        if (!__atomic_load_n(&block, __ATOMIC_RELAXED)) __atomic_store_n(&block, std::uint8_t{1}, __ATOMIC_RELAXED);
    }

    // Appends the set's indices to `out` in increasing order and empties it.
    void take(std::vector<std::int64_t> &out) {
        empty_into([&](std::int64_t i) { out.push_back(i); });
    }

    // The number of indices in the set; empties it.
    std::int64_t take_count() {
        std::int64_t count = 0;
        empty_into([&](std::int64_t) { ++count; });
        return count;
    }

private:
    static constexpr int kShift = 12;
    static constexpr std::size_t kBlock = std::size_t{1} << kShift;
    std::vector<std::uint8_t> marks_, blocks_;

    // Calls visit(i) for every index of the set in increasing order, emptying it.
    template <class Visit>
    void empty_into(const Visit &visit) {
        for (std::size_t b = 0; b < blocks_.size(); ++b) {
            if (!blocks_[b]) continue;
            blocks_[b] = 0;
            std::uint8_t *mark = marks_.data() + (b << kShift);
            for (std::size_t w = 0; w < kBlock; w += 8) {
                std::uint64_t word;
                std::memcpy(&word, mark + w, 8);
                if (!word) continue;
                for (std::size_t k = 0; k < 8; ++k)
                    if (mark[w + k]) visit(static_cast<std::int64_t>((b << kShift) + w + k));
                std::memset(mark + w, 0, 8);
            }
        }
    }
};

}  // namespace dpsm

#endif
