/*
 * heap: the heap an Uno firmware has taken after its first seconds, run in simavr with nothing on
 * its serial port (bench/peers.sh: libraries that allocate do it while starting, from constructors
 * of globals or from begin()).
 *
 *   heap FIRMWARE.elf BRKVAL_ADDR HEAP_START_ADDR [SECONDS]
 *
 * The addresses are the ELF symbols __brkval and __heap_start (avr-nm; the 0x800000 of AVR data
 * addresses is dropped here). Prints one number: __brkval - __heap_start, the bytes malloc took
 * from the free SRAM with its 2-byte block headers, 0 while nothing was allocated.
 */
#include <stdio.h>
#include <stdlib.h>

#include <simavr/sim_avr.h>
#include <simavr/sim_elf.h>
#include <simavr/avr_uart.h>

int main(int argc, char **argv)
{
	if (argc < 4 || argc > 5) {
		fprintf(stderr, "usage: %s FIRMWARE.elf BRKVAL_ADDR HEAP_START_ADDR [SECONDS]\n", argv[0]);
		return 2;
	}
	unsigned long brkval = strtoul(argv[2], NULL, 16) & 0xFFFF;
	unsigned long heap_start = strtoul(argv[3], NULL, 16) & 0xFFFF;
	double seconds = argc == 5 ? atof(argv[4]) : 2.0;

	elf_firmware_t fw = {0};
	if (elf_read_firmware(argv[1], &fw) != 0) {
		fprintf(stderr, "heap: cannot read %s\n", argv[1]);
		return 1;
	}
	avr_t *avr = avr_make_mcu_by_name("atmega328p");
	if (!avr) {
		fprintf(stderr, "heap: simavr has no atmega328p\n");
		return 1;
	}
	avr_init(avr);
	avr_load_firmware(avr, &fw);
	avr->frequency = 16000000;
	if (brkval + 1 > avr->ramend || heap_start > avr->ramend + 1UL) {
		fprintf(stderr, "heap: addresses outside the SRAM\n");
		return 1;
	}
	/* What the firmware prints is not ours to show; nor sleep on every idle UART poll. */
	uint32_t flags = 0;
	avr_ioctl(avr, AVR_IOCTL_UART_GET_FLAGS('0'), &flags);
	flags &= ~(AVR_UART_FLAG_STDIO | AVR_UART_FLAG_POOL_SLEEP);
	avr_ioctl(avr, AVR_IOCTL_UART_SET_FLAGS('0'), &flags);

	avr_cycle_count_t end = (avr_cycle_count_t)(seconds * avr->frequency);
	while (avr->cycle < end) {
		int state = avr_run(avr);
		if (state == cpu_Done || state == cpu_Crashed) {
			fprintf(stderr, "heap: the firmware stopped (state %d) at cycle %llu\n", state,
				(unsigned long long)avr->cycle);
			return 1;
		}
	}
	unsigned brk = avr->data[brkval] | (avr->data[brkval + 1] << 8);
	printf("%lu\n", brk ? brk - heap_start : 0UL);
	return 0;
}
