/* bondcosim FMU: platform settings, included first by the FMI wrappers.

   glibc 2.29 gave exp, exp2, log, log2 and pow new symbol versions (faster
   code, no SVID error handling); a library linked against glibc >= 2.29
   then needs GLIBC_2.29 at load time and does not load on older systems
   (CentOS/RHEL 8 have 2.28).  The old versions still exist in every newer
   glibc and compute the same values (both call the same implementation; the
   old wrapper differs only in errno/matherr handling of domain errors), so
   the binary bondcosim ships binds to them (built with -DBC_GLIBC_COMPAT and
   -lm): it then needs GLIBC_2.2.5 symbols only.  Off by default, because
   binding a versioned symbol needs libm on the link line, and a builder that
   leaves it out (FMI 2.0 sources say nothing about libraries) would fail. */
#ifndef BC_PLATFORM_H
#define BC_PLATFORM_H

#include <math.h>

#if defined(__GLIBC__) && defined(__x86_64__) && defined(BC_GLIBC_COMPAT)
__asm__(".symver exp,exp@GLIBC_2.2.5");
__asm__(".symver exp2,exp2@GLIBC_2.2.5");
__asm__(".symver log,log@GLIBC_2.2.5");
__asm__(".symver log2,log2@GLIBC_2.2.5");
__asm__(".symver pow,pow@GLIBC_2.2.5");
#endif

#endif
