/*
 * Test-only stand-in for Windows' bcryptprimitives.dll, which Wine 8 lacks.
 * Rust's std (>= 1.78) imports ProcessPrng from it for its random hash seeds.
 * fmu/cross_toolchain.sh builds it into the tests' Wine prefix; Windows 10
 * and later have the real DLL, and no FMU ships this one.
 */
#include <windows.h>
#include <ntsecapi.h>

__declspec(dllexport) BOOL WINAPI ProcessPrng(PBYTE data, SIZE_T size)
{
    /* RtlGenRandom (advapi32's SystemFunction036) takes a ULONG length. */
    while (size > 0) {
        ULONG chunk = size > 0x10000000 ? 0x10000000 : (ULONG)size;
        if (!RtlGenRandom(data, chunk)) {
            return FALSE;
        }
        data += chunk;
        size -= chunk;
    }
    return TRUE;
}
