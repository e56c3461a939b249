/* Python's object arenas kept in the process while a compile runs
 * (mechatron.compiler.heap).
 *
 * CPython's small-object allocator takes memory from the kernel in arenas (1 MiB from
 * Python 3.10) and hands an arena back as soon as every object in it is freed. A compile
 * of 10^5 sections frees and maps again some 900 of them: each page of each arena is
 * then a page fault and a page zeroed by the kernel once more. This allocator sits in
 * front of the one installed (CPython's mmap and munmap): while `keeping` is set, an
 * arena handed back is put on a list instead, and the next arena asked for is taken from
 * that list; `mt_arenas_release` hands the listed arenas back through the allocator
 * before. An arena's first bytes hold the list while it is listed (CPython assumes
 * nothing of an arena's content: its malloc fallback gives memory that is not zeroed).
 *
 * CPython calls these functions with the GIL held, and Python calls the three entry
 * points through ctypes.PyDLL, which holds it too: no lock is needed. No Python header
 * is needed either: the allocator's layout (PyObjectArenaAllocator) is part of the
 * stable C API, and Python installs the allocator through ctypes.pythonapi.
 */
#include <stddef.h>

typedef struct {
    void *ctx;
    void *(*alloc)(void *ctx, size_t size);
    void (*free)(void *ctx, void *ptr, size_t size);
} mt_arena_allocator;

typedef struct mt_kept {
    struct mt_kept *next;
    size_t size;
} mt_kept;

static mt_arena_allocator before;       /* the allocator this one sits in front of */
static mt_kept *kept = NULL;            /* arenas handed back while keeping */
static int keeping = 0;
static size_t counts[3];                /* listed now, taken from the list, asked for */

static void *arena_alloc(void *ctx, size_t size)
{
    (void)ctx;
    counts[2]++;
    if (kept != NULL && kept->size == size) {
        mt_kept *arena = kept;
        kept = arena->next;
        counts[0]--;
        counts[1]++;
        return arena;
    }
    return before.alloc(before.ctx, size);
}

static void arena_free(void *ctx, void *ptr, size_t size)
{
    (void)ctx;
    if (keeping && ptr != NULL && size >= sizeof(mt_kept)) {
        mt_kept *arena = ptr;
        arena->next = kept;
        arena->size = size;
        kept = arena;
        counts[0]++;
        return;
    }
    before.free(before.ctx, ptr, size);
}

/* This allocator's functions, and the one it sits in front of (`previous`, read by the
 * caller from PyObject_GetArenaAllocator just before it installs `ours`). If `previous`
 * is this allocator already (installed twice), it stays in front of the one before. */
void mt_arenas_chain(const mt_arena_allocator *previous, mt_arena_allocator *ours)
{
    if (previous->alloc != arena_alloc)
        before = *previous;
    ours->ctx = NULL;
    ours->alloc = arena_alloc;
    ours->free = arena_free;
}

void mt_arenas_keep(int on)
{
    keeping = on;
}

/* Hand every listed arena back; returns how many there were. */
size_t mt_arenas_release(void)
{
    size_t n = 0;
    while (kept != NULL) {
        mt_kept *arena = kept;
        kept = arena->next;
        before.free(before.ctx, arena, arena->size);
        n++;
    }
    counts[0] = 0;
    return n;
}

/* Arenas listed now, taken from the list so far, asked for so far. */
void mt_arenas_counts(size_t out[3])
{
    out[0] = counts[0];
    out[1] = counts[1];
    out[2] = counts[2];
}
