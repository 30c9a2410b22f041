# Sourced by the scripts that run on a GPU host (carry/gpu-sweep/run.sh and smoke.sh).
# find_nvidia_opencl: makes the machine's own ICD loader see NVIDIA's OpenCL. A container image
# may lack the .icd file although the driver brings libnvidia-opencl; none is carried.
find_nvidia_opencl() {
    grep -qsi nvidia /etc/OpenCL/vendors/*.icd && return 0
    local lib
    lib=$(ldconfig -p 2>/dev/null | awk '/libnvidia-opencl\.so\.1/ { print $NF; exit }')
    [ -n "$lib" ] || lib=$(find /usr/local/nvidia /usr/lib /usr/lib64 /usr/local /opt \
                               -name 'libnvidia-opencl.so.1' 2>/dev/null | head -1)
    if [ -z "$lib" ]; then
        echo "== no libnvidia-opencl.so.1 on this machine: no NVIDIA OpenCL platform"
        return 1
    fi
    mkdir -p /tmp/icd && echo "$lib" >/tmp/icd/nvidia.icd
    export OCL_ICD_VENDORS=/tmp/icd
    echo "== NVIDIA OpenCL: $lib (through OCL_ICD_VENDORS=/tmp/icd)"
}
