// Passes over a list of cells or faces (a sparse sub-step's), on the
// threads where the list is long enough. Each item's work must write only
// its own item's values (every pass is a gather), so the results do not
// depend on the threads.
#pragma once

#include <cstdint>
#include <vector>

namespace dpsm {

// Below this many items a pass over a list runs on one thread: an item of
// a list costs several cells of a plain pass (its data lies scattered).
constexpr std::int64_t kListItemsForThreads = 4096;

// Calls work(k, item) for every item of a list and its place k in it.
template <class Work>
void for_each_place(const std::int64_t *items, std::int64_t count, int threads, const Work &work) {
    // Not even a team of one where the list is short: a sparse sub-step
    // makes a dozen passes, and a small pile's take microseconds.
    if (threads < 2 || count < kListItemsForThreads) {
        for (std::int64_t k = 0; k < count; ++k) work(k, items[k]);
        return;
    }
#pragma omp parallel for num_threads(threads) schedule(static)
    for (std::int64_t k = 0; k < count; ++k) work(k, items[k]);
}
template <class Work>
void for_each_place(const std::vector<std::int64_t> &list, int threads, const Work &work) {
    for_each_place(list.data(), static_cast<std::int64_t>(list.size()), threads, work);
}
// The same, work(item) alone.
template <class Work>
void for_each_item(const std::int64_t *items, std::int64_t count, int threads, const Work &work) {
    for_each_place(items, count, threads, [&](std::int64_t, std::int64_t item) { work(item); });
}
template <class Work>
void for_each_item(const std::vector<std::int64_t> &list, int threads, const Work &work) {
    for_each_item(list.data(), static_cast<std::int64_t>(list.size()), threads, work);
}
// Calls work(items, count) for a share of a list a thread (the whole list
// on one thread where it is short): the passes in lanes over a list.
template <class Work>
void for_each_share(const std::int64_t *items, std::int64_t count, int threads, const Work &work) {
    if (threads < 2 || count < kListItemsForThreads) {
        work(items, count);
        return;
    }
    const int shares = threads;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int r = 0; r < shares; ++r) {
        const std::int64_t begin = count * r / shares, end = count * (r + 1) / shares;
        work(items + begin, end - begin);
    }
}
template <class Work>
void for_each_share(const std::vector<std::int64_t> &list, int threads, const Work &work) {
    for_each_share(list.data(), static_cast<std::int64_t>(list.size()), threads, work);
}

}  // namespace dpsm
