/* The extern functions of callorder.rcs in C: the journal of callorder_impl.py. */
#include "callorder.h"

static int64_t s = 0;

static int64_t mix(int64_t v)
{
    s = (s * 31 + v) % 1000003;
    return s;
}

int32_t callorder_t_i32(int32_t k) { return (int32_t)mix(k); }
double callorder_t_f64(double x, int32_t k) { return x + (double)mix(k); }
bool callorder_t_bool(int32_t k) { return mix(k) % 2 == 1; }
callorder_Mode callorder_t_mode(callorder_Mode m, int32_t k) { return (callorder_Mode)(mix((int64_t)k * 4 + m) % 3); }

callorder_Pt callorder_t_pt(callorder_Pt p, int32_t k)
{
    int64_t v = mix((int64_t)k * 7 + (p.a & 1023));
    callorder_Pt out = {(int32_t)(v % 100), p.b + 1.0};
    return out;
}

int64_t callorder_t_dur(int64_t d, int32_t k) { return d + mix(k) * 1000000; }
uint32_t callorder_t_u32(uint32_t u, int32_t k) { return u + (uint32_t)mix(k); }
int64_t callorder_t_i64(int64_t v, int32_t k) { return mix(k) * 1024 + (v & 1023); }

int32_t callorder_t_arr(callorder_ARRAY__i32__3 xs, int32_t k)
{
    mix(k);
    for (int i = 0; i < 3; i++) mix(xs.v[i] & 1023);
    return (int32_t)s;
}

int32_t callorder_pair(int32_t a, int32_t b)
{
    mix(a & 1023);
    return (int32_t)mix(b & 1023);
}

int32_t callorder_peek(void) { return (int32_t)s; }
