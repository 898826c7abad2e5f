/* perf_externs.c (tests/test_perfstat.py): spin busy-waits n iterations and
 * returns 0, as the simulator's stub does, so the traces still agree. */
#include "perf.h"

int32_t perf_spin(int32_t n)
{
    volatile int32_t k = 0;
    for (int32_t i = 0; i < n; i++) k = k + 1;
    return INT32_C(0);
}
