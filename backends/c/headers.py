"""The names the C headers of the generated code declare, for `naming.py` to keep clear of.

The generated translation units include <stdbool.h>, <stddef.h>, <stdint.h>,
<stdio.h> (through rcs_runtime.h) and the runtime's headers; an extern file a
person writes may add <stdlib.h>, <string.h>, <math.h>, <time.h>, <limits.h>,
<float.h> or <inttypes.h>.  `collect()` asks a C compiler for every macro
(`-dM`) and every identifier (`-E`) those headers define in C99, without
the ones that begin with `_` (reserved to the implementation, and never a
name the scheme produces).  The lists below are its output with gcc and clang
on glibc; `tests/test_naming.py` checks that they still cover what the
compilers here define (`python -m rcsc.backends.c.headers` prints fresh
lists).
"""

from __future__ import annotations

import re
import subprocess
import sys
import tempfile

HEADERS = ("stdbool.h", "stddef.h", "stdint.h", "stdio.h", "stdlib.h", "string.h", "math.h", "time.h", "limits.h", "float.h", "inttypes.h")
# Struct members and tags of the headers: not in the scope of a generated name.
_NOT_IN_SCOPE = re.compile(r"(quot|rem|tm|tm_\w+)\Z")


def collect(cc: str) -> tuple[set[str], set[str], set[str]]:
    """(macros, functions, other identifiers) that `cc` defines for the headers, in C99."""
    with tempfile.NamedTemporaryFile("w", suffix=".c") as f:
        f.write("".join(f"#include <{h}>\n" for h in HEADERS))
        f.flush()
        defs = subprocess.run([cc, "-std=c99", "-E", "-dM", f.name], capture_output=True, text=True, check=True).stdout
        text = subprocess.run([cc, "-std=c99", "-E", "-P", f.name], capture_output=True, text=True, check=True).stdout
    macros = {re.split(r"[ (]", line, maxsplit=2)[1] for line in defs.splitlines() if line.startswith("#define ")}
    idents = set(re.findall(r"\b[A-Za-z_]\w*\b", text))
    functions = set(re.findall(r"\b([A-Za-z_]\w*)\s*\(", text))
    keep = lambda s: {x for x in s if not x.startswith("_") and not _NOT_IN_SCOPE.match(x)}  # noqa: E731
    return keep(macros), keep(functions), keep(idents - functions - macros)


MACROS = frozenset("""
BUFSIZ CHAR_BIT CHAR_MAX CHAR_MIN CLOCKS_PER_SEC DBL_DIG DBL_EPSILON DBL_MANT_DIG DBL_MAX
DBL_MAX_10_EXP DBL_MAX_EXP DBL_MIN DBL_MIN_10_EXP DBL_MIN_EXP DECIMAL_DIG EOF EXIT_FAILURE
EXIT_SUCCESS FILENAME_MAX FLT_DIG FLT_EPSILON FLT_EVAL_METHOD FLT_MANT_DIG FLT_MAX FLT_MAX_10_EXP
FLT_MAX_EXP FLT_MIN FLT_MIN_10_EXP FLT_MIN_EXP FLT_RADIX FLT_ROUNDS FOPEN_MAX FP_ILOGB0 FP_ILOGBNAN
FP_INFINITE FP_NAN FP_NORMAL FP_SUBNORMAL FP_ZERO HUGE_VAL HUGE_VALF HUGE_VALL INFINITY INT16_C
INT16_MAX INT16_MIN INT32_C INT32_MAX INT32_MIN INT64_C INT64_MAX INT64_MIN INT8_C INT8_MAX
INT8_MIN INTMAX_C INTMAX_MAX INTMAX_MIN INTPTR_MAX INTPTR_MIN INT_FAST16_MAX INT_FAST16_MIN
INT_FAST32_MAX INT_FAST32_MIN INT_FAST64_MAX INT_FAST64_MIN INT_FAST8_MAX INT_FAST8_MIN
INT_LEAST16_MAX INT_LEAST16_MIN INT_LEAST32_MAX INT_LEAST32_MIN INT_LEAST64_MAX INT_LEAST64_MIN
INT_LEAST8_MAX INT_LEAST8_MIN INT_MAX INT_MIN LDBL_DIG LDBL_EPSILON LDBL_MANT_DIG LDBL_MAX
LDBL_MAX_10_EXP LDBL_MAX_EXP LDBL_MIN LDBL_MIN_10_EXP LDBL_MIN_EXP LLONG_MAX LLONG_MIN LONG_MAX
LONG_MIN L_tmpnam MATH_ERREXCEPT MATH_ERRNO MB_CUR_MAX MB_LEN_MAX NAN NULL PRIX16 PRIX32 PRIX64
PRIX8 PRIXFAST16 PRIXFAST32 PRIXFAST64 PRIXFAST8 PRIXLEAST16 PRIXLEAST32 PRIXLEAST64 PRIXLEAST8
PRIXMAX PRIXPTR PRId16 PRId32 PRId64 PRId8 PRIdFAST16 PRIdFAST32 PRIdFAST64 PRIdFAST8 PRIdLEAST16
PRIdLEAST32 PRIdLEAST64 PRIdLEAST8 PRIdMAX PRIdPTR PRIi16 PRIi32 PRIi64 PRIi8 PRIiFAST16 PRIiFAST32
PRIiFAST64 PRIiFAST8 PRIiLEAST16 PRIiLEAST32 PRIiLEAST64 PRIiLEAST8 PRIiMAX PRIiPTR PRIo16 PRIo32
PRIo64 PRIo8 PRIoFAST16 PRIoFAST32 PRIoFAST64 PRIoFAST8 PRIoLEAST16 PRIoLEAST32 PRIoLEAST64
PRIoLEAST8 PRIoMAX PRIoPTR PRIu16 PRIu32 PRIu64 PRIu8 PRIuFAST16 PRIuFAST32 PRIuFAST64 PRIuFAST8
PRIuLEAST16 PRIuLEAST32 PRIuLEAST64 PRIuLEAST8 PRIuMAX PRIuPTR PRIx16 PRIx32 PRIx64 PRIx8
PRIxFAST16 PRIxFAST32 PRIxFAST64 PRIxFAST8 PRIxLEAST16 PRIxLEAST32 PRIxLEAST64 PRIxLEAST8 PRIxMAX
PRIxPTR PTRDIFF_MAX PTRDIFF_MIN RAND_MAX SCHAR_MAX SCHAR_MIN SCNd16 SCNd32 SCNd64 SCNd8 SCNdFAST16
SCNdFAST32 SCNdFAST64 SCNdFAST8 SCNdLEAST16 SCNdLEAST32 SCNdLEAST64 SCNdLEAST8 SCNdMAX SCNdPTR
SCNi16 SCNi32 SCNi64 SCNi8 SCNiFAST16 SCNiFAST32 SCNiFAST64 SCNiFAST8 SCNiLEAST16 SCNiLEAST32
SCNiLEAST64 SCNiLEAST8 SCNiMAX SCNiPTR SCNo16 SCNo32 SCNo64 SCNo8 SCNoFAST16 SCNoFAST32 SCNoFAST64
SCNoFAST8 SCNoLEAST16 SCNoLEAST32 SCNoLEAST64 SCNoLEAST8 SCNoMAX SCNoPTR SCNu16 SCNu32 SCNu64 SCNu8
SCNuFAST16 SCNuFAST32 SCNuFAST64 SCNuFAST8 SCNuLEAST16 SCNuLEAST32 SCNuLEAST64 SCNuLEAST8 SCNuMAX
SCNuPTR SCNx16 SCNx32 SCNx64 SCNx8 SCNxFAST16 SCNxFAST32 SCNxFAST64 SCNxFAST8 SCNxLEAST16
SCNxLEAST32 SCNxLEAST64 SCNxLEAST8 SCNxMAX SCNxPTR SEEK_CUR SEEK_END SEEK_SET SHRT_MAX SHRT_MIN
SIG_ATOMIC_MAX SIG_ATOMIC_MIN SIZE_MAX TMP_MAX UCHAR_MAX UINT16_C UINT16_MAX UINT32_C UINT32_MAX
UINT64_C UINT64_MAX UINT8_C UINT8_MAX UINTMAX_C UINTMAX_MAX UINTPTR_MAX UINT_FAST16_MAX
UINT_FAST32_MAX UINT_FAST64_MAX UINT_FAST8_MAX UINT_LEAST16_MAX UINT_LEAST32_MAX UINT_LEAST64_MAX
UINT_LEAST8_MAX UINT_MAX ULLONG_MAX ULONG_MAX USHRT_MAX WCHAR_MAX WCHAR_MIN WINT_MAX WINT_MIN bool
false fpclassify isfinite isgreater isgreaterequal isinf isless islessequal islessgreater isnan
isnormal isunordered math_errhandling offsetof signbit stderr stdin stdout true va_arg va_copy
va_end va_start
""".split())
FUNCTIONS = frozenset("""
abort abs acos acosf acosh acoshf acoshl acosl asctime asin asinf asinh asinhf asinhl asinl atan
atan2 atan2f atan2l atanf atanh atanhf atanhl atanl atexit atof atoi atol atoll bsearch calloc cbrt
cbrtf cbrtl ceil ceilf ceill clearerr clock copysign copysignf copysignl cos cosf cosh coshf coshl
cosl ctime difftime div erf erfc erfcf erfcl erff erfl exit exp exp2 exp2f exp2l expf expl expm1
expm1f expm1l fabs fabsf fabsl fclose fdim fdimf fdiml feof ferror fflush fgetc fgetpos fgets floor
floorf floorl fma fmaf fmal fmax fmaxf fmaxl fmin fminf fminl fmod fmodf fmodl fopen fprintf fputc
fputs fread free freopen frexp frexpf frexpl fscanf fseek fsetpos ftell fwrite getc getchar getenv
gets gmtime hypot hypotf hypotl ilogb ilogbf ilogbl imaxabs imaxdiv int labs ldexp ldexpf ldexpl
ldiv lgamma lgammaf lgammal llabs lldiv llrint llrintf llrintl llround llroundf llroundl localtime
log log10 log10f log10l log1p log1pf log1pl log2 log2f log2l logb logbf logbl logf logl lrint
lrintf lrintl lround lroundf lroundl malloc mblen mbstowcs mbtowc memchr memcmp memcpy memmove
memset mktime modf modff modfl nan nanf nanl nearbyint nearbyintf nearbyintl nextafter nextafterf
nextafterl nexttoward nexttowardf nexttowardl perror pow powf powl printf putc putchar puts qsort
rand realloc remainder remainderf remainderl remove remquo remquof remquol rename rewind rint rintf
rintl round roundf roundl scalbln scalblnf scalblnl scalbn scalbnf scalbnl scanf setbuf setvbuf sin
sinf sinh sinhf sinhl sinl sizeof snprintf sprintf sqrt sqrtf sqrtl srand sscanf strcat strchr
strcmp strcoll strcpy strcspn strerror strftime strlen strncat strncmp strncpy strpbrk strrchr
strspn strstr strtod strtof strtoimax strtok strtol strtold strtoll strtoul strtoull strtoumax
strxfrm system tan tanf tanh tanhf tanhl tanl tgamma tgammaf tgammal time tmpfile tmpnam trunc
truncf truncl ungetc vfprintf vfscanf void vprintf vscanf vsnprintf vsprintf vsscanf wcstoimax
wcstombs wcstoumax wctomb
""".split())
OTHERS = frozenset("""
FILE char clock_t const div_t double double_t enum extern float float_t fpos_t imaxdiv_t int16_t
int32_t int64_t int8_t int_fast16_t int_fast32_t int_fast64_t int_fast8_t int_least16_t
int_least32_t int_least64_t int_least8_t intmax_t intptr_t ldiv_t lldiv_t long ptrdiff_t short
signed size_t struct time_t typedef uint16_t uint32_t uint64_t uint8_t uint_fast16_t uint_fast32_t
uint_fast64_t uint_fast8_t uint_least16_t uint_least32_t uint_least64_t uint_least8_t uintmax_t
uintptr_t union unsigned va_list wchar_t
""".split())


if __name__ == "__main__":
    ms, fs, os_ = set(), set(), set()
    for compiler in sys.argv[1:] or ["gcc", "clang"]:
        m, f, o = collect(compiler)
        ms |= m
        fs |= f
        os_ |= o
    for name, items in (("MACROS", ms), ("FUNCTIONS", fs), ("OTHERS", os_)):
        print(f"{name} = frozenset(\"\"\"")
        line = ""
        for x in sorted(items):
            if len(line) + len(x) + 1 > 100:
                print(line.rstrip())
                line = ""
            line += x + " "
        print(line.rstrip())
        print('""".split())')
