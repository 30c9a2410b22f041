// rtlab — --queue-shade sort (included by queue.cl): a counting sort of the bounce's hits by
// material id, so that Queue_ShadeSorted's neighbouring work-items shade the same material
// (Cycles sorts its paths by shader the same way before surface shading). Three kernels over
// the hit queue extend filled (RT_Q_HITS): count the hits per material, scan the counts into
// each material's first slot (the scan of queue_scan.cl), and scatter every hit to a slot of its
// material's run in the sorted queue (RT_Q_SORTED). The order within a run is that of atomics,
// as the class queues' is: each result is written at the ray's own pool index, so it changes no
// pixel.

// Materials below this id are counted per work-group in local memory first and reserved in
// the global counts once per group, as extend's pushes are (Queue_GroupPushesReserve): on a GPU
// the few materials of a scene would otherwise take every lane's atomic on the same words.
#define RT_Q_SORT_LOCAL_KEYS 64

inline void Queue_SortLocalBegin(local int* count, int lid, int size) {
    for (int j = lid; j < RT_Q_SORT_LOCAL_KEYS; j += size) count[j] = 0;
    barrier(CLK_LOCAL_MEM_FENCE);
}

// From: hit queue, nodes / To: keys[m] += the hits on material m (keys zeroed by the host).
kernel void Queue_SortCount(global const Node* nodes, global const int* shadeQueues, int pool,
                            global const int* counters, global int* keys) {
    local int count[RT_Q_SORT_LOCAL_KEYS];
    int k = get_global_id(0), lid = get_local_id(0), size = get_local_size(0);
    int n = counters[RT_Q_COUNT + RT_Q_HITS];
    if (k - lid >= n) return;  // a whole group past the queue: no barrier is left half-reached
    Queue_SortLocalBegin(count, lid, size);
    int key = k < n ? nodes[shadeQueues[RT_Q_HITS * pool + k]].material : -1;
    if (key >= RT_Q_SORT_LOCAL_KEYS)
        atomic_inc(&keys[key]);
    else if (key >= 0)
        atomic_inc(&count[key]);
    barrier(CLK_LOCAL_MEM_FENCE);
    for (int j = lid; j < RT_Q_SORT_LOCAL_KEYS; j += size)
        if (count[j]) atomic_add(&keys[j], count[j]);
}

// One work-group. From: hits per material / To: keys[m] = the first slot of material m's run.
kernel void Queue_SortBuckets(global int* keys, int materials) {
    local int tmp[RT_QUEUE_GROUP];
    Queue_ScanInPlace(tmp, get_local_id(0), keys, materials);
}

// From: hit queue, nodes, each material's next slot / To: the sorted queue. A group's hits on
// one material take consecutive slots of its run.
kernel void Queue_SortScatter(global const Node* nodes, global int* shadeQueues, int pool,
                              global const int* counters, global int* keys) {
    local int count[RT_Q_SORT_LOCAL_KEYS], base[RT_Q_SORT_LOCAL_KEYS];
    int k = get_global_id(0), lid = get_local_id(0), size = get_local_size(0);
    int n = counters[RT_Q_COUNT + RT_Q_HITS];
    if (k - lid >= n) return;
    Queue_SortLocalBegin(count, lid, size);
    int i = -1, key = -1, slot = 0;
    if (k < n) {
        i = shadeQueues[RT_Q_HITS * pool + k];
        key = nodes[i].material;
        if (key < RT_Q_SORT_LOCAL_KEYS) slot = atomic_inc(&count[key]);
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    for (int j = lid; j < RT_Q_SORT_LOCAL_KEYS; j += size)
        if (count[j]) base[j] = atomic_add(&keys[j], count[j]);
    barrier(CLK_LOCAL_MEM_FENCE);
    if (key >= RT_Q_SORT_LOCAL_KEYS)
        shadeQueues[RT_Q_SORTED * pool + atomic_inc(&keys[key])] = i;
    else if (key >= 0)
        shadeQueues[RT_Q_SORTED * pool + base[key] + slot] = i;
}
