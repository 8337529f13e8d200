// Marks functions shared by the TBB (host) and CUDA (device) paths: kernels are written once.
#pragma once

#if defined(__CUDACC__)
#define VL_HOSTDEV __host__ __device__
#else
#define VL_HOSTDEV
#endif
