// rtlab — a work-group's inclusive prefix sum in local memory (Hillis and Steele: log2(size)
// steps), for the kernels that compact rays in a stable order: the queue wavefront's scan and the
// persistent megakernel's bounce loop. Every work-item of the group calls it.
#ifndef RTLAB_CL_SCAN
#define RTLAB_CL_SCAN

// Lane lid's v plus the v of every lower lane; `tmp` holds `size` ints (the group's lanes).
inline int Scan_WorkGroupInclusive(local int* tmp, int lid, int size, int v) {
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

#endif
