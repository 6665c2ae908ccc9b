/* Minimal start-up for the check program on QEMU's MPS2 Cortex-M boards (cortex_m.ld):
 * the vector table, then copy .data, zero .bss, enable the FPU, open newlib's semihosting
 * streams (librdimon, --specs=rdimon.specs) and run main. Its exit status leaves QEMU through
 * semihosting's exit call. */
#include <stdint.h>
#include <stdlib.h>

extern uint32_t __etext, __data_start__, __data_end__, __bss_start__, __bss_end__;
extern void __stack_top__(void); /* a linker-script address, declared as a function to fit the table */
extern int main(void);
extern void initialise_monitor_handles(void);
void qd_reset(void);
void qd_fault(void);

/* initial stack pointer, reset, NMI, hard fault, memory management, bus and usage faults */
__attribute__((section(".qd_vectors"), used)) static void (*const qd_vectors[16])(void) = {
    __stack_top__, qd_reset, qd_fault, qd_fault, qd_fault, qd_fault, qd_fault};

void qd_fault(void) { exit(99); }

/* newlib's exit runs __libc_fini_array, which calls _fini (crti.o's, left out with -nostartfiles) */
void _init(void);
void _fini(void);
void _init(void) {}
void _fini(void) {}

void qd_reset(void) {
  for (uint32_t *src = &__etext, *dst = &__data_start__; dst < &__data_end__;) *dst++ = *src++;
  for (uint32_t* dst = &__bss_start__; dst < &__bss_end__;) *dst++ = 0;
#if defined(__ARM_FP)
  *(volatile uint32_t*)0xE000ED88u |= 0xFu << 20; /* CPACR: full access to CP10, CP11 (the FPU) */
  __asm__ volatile("dsb\n\tisb" ::: "memory");
#endif
  initialise_monitor_handles();
  exit(main());
}
