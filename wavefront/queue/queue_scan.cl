// rtlab — the queue wavefront's bookkeeping kernels (included by queue.cl): the prefix sum that
// compacts the children into the next queue in a stable order, the cut that keeps that queue
// within the pool, and the per-pixel sums. RT_QUEUE_GROUP is the work-group size of the scan,
// a power of two the host picks for the device.

// Inclusive scan of one work-group's values in local memory (Hillis-Steele: log2(size) steps).
inline int Queue_ScanLocal(local int* tmp, int lid, int size, int v) {
    tmp[lid] = v;
    barrier(CLK_LOCAL_MEM_FENCE);
    for (int off = 1; off < size; off <<= 1) {
        int t = lid >= off ? tmp[lid - off] : 0;
        barrier(CLK_LOCAL_MEM_FENCE);
        tmp[lid] += t;
        barrier(CLK_LOCAL_MEM_FENCE);
    }
    return tmp[lid];
}

// From: children per ray / To: offsets within the work-group's block, and each block's total.
kernel void Queue_ScanBlocks(global const int* children, int n, global int* offsets,
                             global int* blockSums, global const int* counters, int nWord) {
    local int tmp[RT_QUEUE_GROUP];
    int i = get_global_id(0), lid = get_local_id(0);
    n = Queue_Length(n, nWord, counters);
    // The block is counted from the global index, not get_group_id, which restarts at 0 in each
    // piece of a launch split by --max-launch-ms (pieces start at a global offset).
    int block = (i - lid) / RT_QUEUE_GROUP;
    if (block * RT_QUEUE_GROUP >= n) return;  // past the queue: Queue_ScanSums skips it
    int v = i < n ? children[i] : 0;
    int inclusive = Queue_ScanLocal(tmp, lid, RT_QUEUE_GROUP, v);
    if (i < n) offsets[i] = inclusive - v;
    if (lid == RT_QUEUE_GROUP - 1) blockSums[block] = inclusive;
}

// One work-group (every work-item calls it): values[0, count) to their exclusive prefix sums,
// in chunks of the group; returns the total.
inline int Queue_ScanInPlace(local int* tmp, int lid, global int* values, int count) {
    int carry = 0;
    for (int b0 = 0; b0 < count; b0 += RT_QUEUE_GROUP) {
        int b = b0 + lid;
        int v = b < count ? values[b] : 0;
        int inclusive = Queue_ScanLocal(tmp, lid, RT_QUEUE_GROUP, v);
        if (b < count) values[b] = carry + inclusive - v;
        carry += tmp[RT_QUEUE_GROUP - 1];
        barrier(CLK_LOCAL_MEM_FENCE);  // tmp is rewritten by the next chunk
    }
    return carry;
}

// One work-group: block totals to exclusive block offsets, and the grand total to the counters.
// liveWord >= 0 (launches sized on the device): the total also becomes the next bounce's length,
// and the rays to accumulate and compact (RT_Q_CUT) are all of this bounce's, unless the children
// outgrow the pool: then nothing more of this wave runs and RT_Q_OVERFLOW tells the host.
kernel void Queue_ScanSums(global int* blockSums, int blocks, global int* counters, int liveWord,
                           int pool) {
    local int tmp[RT_QUEUE_GROUP];
    int lid = get_local_id(0);
    // Launches sized by a bound: the blocks past the queue's real length were not scanned.
    if (liveWord >= 0)
        blocks = min(blocks, (counters[liveWord] + RT_QUEUE_GROUP - 1) / RT_QUEUE_GROUP);
    int carry = Queue_ScanInPlace(tmp, lid, blockSums, blocks);
    if (lid == 0) counters[RT_Q_CHILDREN] = carry;
    if (lid == 0 && liveWord >= 0) {
        bool fits = carry <= pool;
        counters[RT_Q_CUT] = fits ? counters[liveWord] : 0;
        counters[liveWord] = fits ? carry : 0;
        if (!fits) counters[RT_Q_OVERFLOW] = 1;
    }
}

inline int Queue_Offset(global const int* offsets, global const int* blockSums, int i) {
    return offsets[i] + blockSums[i / RT_QUEUE_GROUP];
}

// One work-item, only when the children outgrow the pool: the last whole paths whose children
// do not fit are cut (the host issues their pixels again later). Children end at inclusive
// offsets that never decrease, so the first ray past the pool is found by bisection, then the
// cut moves back to the first ray of its path.
kernel void Queue_FindCut(global const int* children, global const int* offsets,
                          global const int* blockSums, global const int* pixels, int n, int pool,
                          global int* counters) {
    if (get_global_id(0) != 0) return;
    int lo = 0, hi = n - 1;  // the answer is in [lo, hi]: the total is over the pool
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (Queue_Offset(offsets, blockSums, mid) + children[mid] > pool)
            hi = mid;
        else
            lo = mid + 1;
    }
    int cut = lo;
    while (cut > 0 && pixels[cut - 1] == pixels[lo]) --cut;
    counters[RT_Q_CUT] = cut;
    counters[RT_Q_KEPT] = cut > 0 ? Queue_Offset(offsets, blockSums, cut) : 0;
}

// From: contrib of rays [0, cut) (cut: see Queue_Length) / To: the pixel's running sum of this AA
// sample. The first ray of each path's run adds the run in pool order; a path's first bounce starts
// the sum from zero, as the megakernel's colour does. Ray counts: a run whose rays have no children
// ends its path, whose rays (the pixel's tally, queue.cl) then join the frame's counters.
kernel void Queue_Accumulate(global const int* pixels, global const int* meta,
                             global const float* contrib, int cut, global float* sums,
                             global const int* counters, int cutWord, global const int* children,
                             global uint* rayCounts, global uint* rayTally) {
    int i = get_global_id(0);
    cut = Queue_Length(cut, cutWord, counters);
    if (i >= cut) return;
    int pixel = pixels[i];
    if (i > 0 && pixels[i - 1] == pixel) return;
    float3 s = (meta[i] >> 8) == 0 ? (float3)(0.0f, 0.0f, 0.0f) : vload3(pixel, sums);
    int spawned = 0;
    for (int j = i; j < cut && pixels[j] == pixel; ++j) {
        s += vload3(j, contrib);
        spawned += children[j];
    }
    vstore3(s, pixel, sums);
#ifdef RT_COUNT_RAYS
    if (spawned == 0) {
        global uint* tally = Queue_PixelRays(rayTally, pixel);
        for (int t = 0; t < RT_RAY_TYPES; ++t) {
            if (tally[t]) atomic_add(&rayCounts[t], tally[t]);
            tally[t] = 0;
        }
    }
#endif
}

// From: staging slots of rays [0, cut) / To: the pool's front, at the prefix-sum offsets.
kernel void Queue_Compact(QUEUE_RAYS_PARAMS(staging), global const int* children,
                          global const int* offsets, global const int* blockSums, int cut,
                          QUEUE_RAYS_PARAMS(rays), global const int* counters, int cutWord) {
    int i = get_global_id(0);
    cut = Queue_Length(cut, cutWord, counters);
    if (i >= cut || children[i] == 0) return;
    QUEUE_RAYS_INIT(staging);
    QUEUE_RAYS_INIT(rays);
    int o = Queue_Offset(offsets, blockSums, i);
    for (int k = 0; k < children[i]; ++k) {
        int s = RT_BRANCH * i + k;
        RayState_Copy(&staging.state, s, &rays.state, o + k);
        rays.pixel[o + k] = staging.pixel[s];
    }
}

// From: the finished sums of AA sample `sample` / To: the image. The first sample stores, later
// ones add, the last divides: the megakernel's sum over samples, in the same order.
kernel void Queue_Resolve(global const float* sums, global float* image, int pixels, int sample,
                          int samples) {
    int i = get_global_id(0);
    if (i >= pixels) return;
    float3 c = vload3(i, sums);
    if (sample > 0) c += vload3(i, image);
    if (sample == samples - 1) c = c / (float)samples;
    vstore3(c, i, image);
}
