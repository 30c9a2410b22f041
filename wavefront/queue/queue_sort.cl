// rtlab — --queue-shade sort (included by queue.cl): a counting sort of the bounce's hits by
// material id, so that Queue_ShadeSorted's neighbouring work-items shade the same material
// (Cycles sorts its paths by shader the same way before surface shading). Three kernels over
// the hit queue extend filled (RT_Q_HITS): count the hits per material, scan the counts into
// each material's first slot (the scan of queue_scan.cl), and scatter every hit to a slot of its
// material's run in the sorted queue (RT_Q_SORTED). The order within a run is that of atomics,
// as the class queues' is: each result is written at the ray's own pool index, so it changes no
// pixel.

// From: hit queue, nodes / To: keys[m] += the hits on material m (keys zeroed by the host).
kernel void Queue_SortCount(global const Node* nodes, global const int* shadeQueues, int pool,
                            global const int* counters, global int* keys) {
    int k = get_global_id(0);
    if (k >= counters[RT_Q_COUNT + RT_Q_HITS]) return;
    atomic_inc(&keys[nodes[shadeQueues[RT_Q_HITS * pool + k]].material]);
}

// One work-group. From: hits per material / To: keys[m] = the first slot of material m's run.
kernel void Queue_SortBuckets(global int* keys, int materials) {
    local int tmp[RT_QUEUE_GROUP];
    Queue_ScanInPlace(tmp, get_local_id(0), keys, materials);
}

// From: hit queue, nodes, each material's next slot / To: the sorted queue.
kernel void Queue_SortScatter(global const Node* nodes, global int* shadeQueues, int pool,
                              global const int* counters, global int* keys) {
    int k = get_global_id(0);
    if (k >= counters[RT_Q_COUNT + RT_Q_HITS]) return;
    int i = shadeQueues[RT_Q_HITS * pool + k];
    shadeQueues[RT_Q_SORTED * pool + atomic_inc(&keys[nodes[i].material])] = i;
}
