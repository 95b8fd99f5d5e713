#ifndef DPSM_MESH_INDEX_SET_HPP
#define DPSM_MESH_INDEX_SET_HPP

// A set of cells or faces that a sparse sub-step builds from the lists before
// it ("the owned cells of these faces"), listed in increasing order: in the
// mesh's Hilbert order, so that the passes over the list read memory near
// where they read last. A byte marks each index and a byte each block of
// 512 indices, so that listing reads only the blocks something was added to.
// Adding from several threads at once is safe (relaxed atomic stores of the
// same value); listing empties the set, the blocks shared between the
// threads in order, so that the list is the same on any number of them.

#include <algorithm>
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

    // The mark is stored whether or not it is there: a test first, its answer
    // as scattered as the marks, cost a mispredicted branch on many adds.
    void add(std::int64_t i) {
        __atomic_store_n(&marks_[static_cast<std::size_t>(i)], std::uint8_t{1}, __ATOMIC_RELAXED);
        std::uint8_t &block = blocks_[static_cast<std::size_t>(i >> kShift)];
        if (!__atomic_load_n(&block, __ATOMIC_RELAXED)) __atomic_store_n(&block, std::uint8_t{1}, __ATOMIC_RELAXED);
    }

    // Appends the set's indices to `out` in increasing order and empties
    // it; the blocks shared between the threads where there are many.
    void take(std::vector<std::int64_t> &out, int threads) {
        list_blocks();
        const int shares = shares_for(threads);
        if (shares == 1) {
            for (const std::size_t b : dirty_) empty_block(b, [&](std::int64_t i) { out.push_back(i); });
            return;
        }
        parts_.resize(static_cast<std::size_t>(shares));
#pragma omp parallel for num_threads(shares) schedule(static)
        for (int r = 0; r < shares; ++r) {
            std::vector<std::int64_t> &part = parts_[static_cast<std::size_t>(r)];
            part.clear();
            for_share(r, shares, [&](std::size_t b) { empty_block(b, [&](std::int64_t i) { part.push_back(i); }); });
        }
        for (const std::vector<std::int64_t> &part : parts_) out.insert(out.end(), part.begin(), part.end());
    }

    // The number of indices in the set; empties it.
    std::int64_t take_count(int threads) {
        list_blocks();
        const int shares = shares_for(threads);
        std::int64_t count = 0;
        const auto count_share = [&](int r) {
            std::int64_t in_share = 0;
            for_share(r, shares, [&](std::size_t b) { empty_block(b, [&](std::int64_t) { ++in_share; }); });
            return in_share;
        };
        if (shares == 1) return count_share(0);
#pragma omp parallel for num_threads(shares) schedule(static) reduction(+ : count)
        for (int r = 0; r < shares; ++r) count += count_share(r);
        return count;
    }

private:
    // Blocks of 512: a small set (a pile of a few hundred cells) reads a
    // few blocks of 64 words; a large one reads its blocks' flags a word at
    // a time.
    static constexpr int kShift = 9;
    static constexpr std::size_t kBlock = std::size_t{1} << kShift;
    // Below this many blocks to read out, one thread does.
    static constexpr std::size_t kBlocksForThreads = 64;
    std::vector<std::uint8_t> marks_, blocks_;
    std::vector<std::size_t> dirty_;                 // the blocks being read out
    std::vector<std::vector<std::int64_t>> parts_;  // a thread's share of the list

    void list_blocks() {
        dirty_.clear();
        for (std::size_t w = 0; w < blocks_.size(); w += 8) {
            std::uint64_t word = 0;
            std::memcpy(&word, blocks_.data() + w, std::min<std::size_t>(8, blocks_.size() - w));
            if (!word) continue;
            for (std::size_t b = w; b < std::min(w + 8, blocks_.size()); ++b)
                if (blocks_[b]) blocks_[b] = 0, dirty_.push_back(b);
        }
    }
    int shares_for(int threads) const { return threads > 1 && dirty_.size() >= kBlocksForThreads ? threads : 1; }
    template <class Visit>
    void for_share(int r, int shares, const Visit &visit) const {
        const std::size_t n = dirty_.size();
        for (std::size_t k = n * static_cast<std::size_t>(r) / static_cast<std::size_t>(shares);
             k < n * static_cast<std::size_t>(r + 1) / static_cast<std::size_t>(shares); ++k)
            visit(dirty_[k]);
    }
    // Calls visit(i) for every index of block b in increasing order, emptying
    // it. A mark is the byte 1, so a word of eight marks read with byte k at
    // bits 8 k has bit 8 k set for each index k it holds: its set bits, lowest
    // first, are its indices in order: read so, without a branch per byte,
    // which the scattered marks of a sparse sub-step's lists mispredict
    // (docs/performance.md, "The lists read out by their bits").
    template <class Visit>
    void empty_block(std::size_t b, const Visit &visit) {
        std::uint8_t *mark = marks_.data() + (b << kShift);
        const std::int64_t first = static_cast<std::int64_t>(b << kShift);
        for (std::size_t w = 0; w < kBlock; w += 8) {
            std::uint64_t word;
            std::memcpy(&word, mark + w, 8);
            if (!word) continue;
            std::memset(mark + w, 0, 8);
#if __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
            word = __builtin_bswap64(word);  // byte k at bits 8 k, as on little-endian machines
#endif
            for (; word; word &= word - 1)
                visit(first + static_cast<std::int64_t>(w) + (__builtin_ctzll(word) >> 3));
        }
    }
};

}  // namespace dpsm

#endif
