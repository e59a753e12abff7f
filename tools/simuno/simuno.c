/*
 * simuno: run real AVR firmware (an Arduino Uno sketch, by default) in simavr
 * with UART0 bridged to a pseudo-terminal, in (approximately) real time.
 *
 *   simuno FIRMWARE.elf --link PATH [--mcu atmega328p] [--freq 16000000]
 *          [--cycles-log FILE] [--fast] [--boot-delay MS] [--reset-on-open]
 *          [--watch-pins]
 *
 * Stdout carries exactly one line, "READY PATH", once the simulation runs.
 * Everything libsimavr prints goes to stderr.
 *
 * Signals: SIGUSR1 resets the MCU (like the DTR auto-reset when a host opens
 * an Uno's port); SIGUSR2 presses or releases a button on PD2 (Arduino pin 2),
 * which otherwise reads high, as INPUT_PULLUP makes it on a real board; SIGTERM / SIGINT / SIGHUP stop cleanly (symlink removed,
 * exit status 0). With --reset-on-open, any open() of the pty resets the MCU
 * too (inotify IN_OPEN on the slave device), as a real Uno does. With
 * --watch-pins, every change of Arduino pins 2..13 as the firmware drives them
 * goes to stderr as "simuno: pin N = V at cycle C" (what a probe would see).
 *
 * Part of Hubwire. Links against Debian's libsimavr / libsimavrparts.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/inotify.h>
#include <sys/stat.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include <simavr/sim_avr.h>
#include <simavr/sim_elf.h>
#include <simavr/sim_io.h>
#include <simavr/sim_irq.h>
#include <simavr/sim_time.h>
#include <simavr/avr_ioport.h>
#include <simavr/avr_uart.h>
#include <simavr/parts/uart_pty.h>

/* GPIOR0 is I/O address 0x1E, data address 0x3E, on the ATmega328P, the
 * ATmega2560 and the ATmega32U4 alike. */
#define GPIOR0_DATA_ADDR 0x3E

/* Lag beyond which we stop trying to catch up with the wall clock. */
#define MAX_LAG_NS (250LL * 1000 * 1000)
/* Instructions between two housekeeping passes (throttle, signals, opens). */
#define RUN_BATCH 2048

static volatile sig_atomic_t g_stop = 0;
static volatile sig_atomic_t g_reset = 0;

static void on_stop(int sig) { (void)sig; g_stop = 1; }
static void on_reset(int sig) { (void)sig; g_reset = 1; }
static volatile sig_atomic_t g_button_toggles = 0;
static void on_button(int sig) { (void)sig; g_button_toggles = g_button_toggles + 1; }

/* ---- cycle log (GPIOR0 writes) ---------------------------------------- */
static FILE *cycles_log = NULL;

static void gpior0_write_hook(struct avr_t *avr, avr_io_addr_t addr, uint8_t v, void *param)
{
	(void)param;
	avr->data[addr] = v; /* keep the register readable by the firmware */
	if (cycles_log) {
		fprintf(cycles_log, "%u %llu\n", (unsigned)v, (unsigned long long)avr->cycle);
		fflush(cycles_log);
	}
}

/* The default raw sleep callback usleep()s; our wall-clock sync below does
 * the waiting for sleeping and running firmware alike. */
static void sleep_noop(avr_t *avr, avr_cycle_count_t how_long) { (void)avr; (void)how_long; }

static int64_t now_ns(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

static void usage(FILE *f)
{
	fprintf(f,
		"usage: simuno FIRMWARE.elf --link PATH [--mcu atmega328p] [--freq 16000000]\n"
		"              [--cycles-log FILE] [--fast] [--boot-delay MS] [--reset-on-open]\n"
		"              [--watch-pins]\n"
		"  --link PATH        make PATH a symlink to the pty bridged to UART0\n"
		"  --mcu NAME         simavr core name (default atmega328p)\n"
		"  --freq HZ          clock frequency (default 16000000)\n"
		"  --cycles-log FILE  append 'value cycle' for every write to GPIOR0\n"
		"  --fast             do not throttle to wall-clock time\n"
		"  --boot-delay MS    after a reset (SIGUSR1 or open), hold the MCU for MS\n"
		"                     milliseconds and swallow incoming bytes (bootloader)\n"
		"  --reset-on-open    reset the MCU whenever a process opens the pty, like\n"
		"                     the DTR auto-reset of a real Uno\n"
		"  --watch-pins       log every change of Arduino pins 2..13 to stderr\n"
		"signals: SIGUSR1 reset the MCU, SIGTERM/SIGINT stop (exit 0)\n");
}

/* The fifo accessors are static inlines instantiated by simavr's own macro. */
DEFINE_FIFO(uint8_t, uart_pty_fifo);

/* Drop what the host sent but the AVR has not received yet, and what the AVR
 * sent that the host has not read (stale bytes from before a reset).
 * Simulation thread only: it is the consumer of pty.out. */
static void discard_input(uart_pty_t *p)
{
	tcflush(p->port[0].s, TCIOFLUSH);
	while (!uart_pty_fifo_isempty(&p->pty.out))
		(void)uart_pty_fifo_read(&p->pty.out);
}

static const char *link_path = NULL;
static int pty_master = -1;
static char slave_name[sizeof(((uart_pty_port_t *)0)->slavename)];

static void remove_link_if_ours(const char *path)
{
	char target[PATH_MAX];
	if (!path)
		return;
	ssize_t n = readlink(path, target, sizeof(target) - 1);
	if (n >= 0) {
		target[n] = 0;
		if (strcmp(target, slave_name) == 0)
			unlink(path);
	}
}

/* --watch-pins: one record per Arduino pin 2..13 (PD2..PD7, PB0..PB5). */
struct watched_pin {
	avr_t *avr;
	int number;
};
static struct watched_pin watched[12];

static void pin_changed(struct avr_irq_t *irq, uint32_t value, void *param)
{
	(void)irq;
	const struct watched_pin *w = param;
	fprintf(stderr, "simuno: pin %d = %u at cycle %llu\n", w->number, (unsigned)value,
		(unsigned long long)w->avr->cycle);
}

static void watch_pins(avr_t *avr)
{
	for (int n = 2; n <= 13; n++) {
		struct watched_pin *w = &watched[n - 2];
		w->avr = avr;
		w->number = n;
		avr_irq_t *irq = avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ(n < 8 ? 'D' : 'B'), n < 8 ? n : n - 8);
		if (irq)
			avr_irq_register_notify(irq, pin_changed, w);
	}
}

int main(int argc, char **argv)
{
	const char *elf = NULL, *mcu = "atmega328p", *log_path = NULL;
	unsigned long freq = 16000000UL;
	int fast = 0, reset_on_open = 0, watch = 0;
	long boot_delay_ms = 0;

	for (int i = 1; i < argc; i++) {
		const char *a = argv[i];
		int more = i + 1 < argc;
		if (!strcmp(a, "-h") || !strcmp(a, "--help")) { usage(stdout); return 0; }
		else if (!strcmp(a, "--link") && more) link_path = argv[++i];
		else if (!strcmp(a, "--mcu") && more) mcu = argv[++i];
		else if (!strcmp(a, "--freq") && more) freq = strtoul(argv[++i], NULL, 0);
		else if (!strcmp(a, "--cycles-log") && more) log_path = argv[++i];
		else if (!strcmp(a, "--boot-delay") && more) boot_delay_ms = strtol(argv[++i], NULL, 0);
		else if (!strcmp(a, "--fast")) fast = 1;
		else if (!strcmp(a, "--reset-on-open")) reset_on_open = 1;
		else if (!strcmp(a, "--watch-pins")) watch = 1;
		else if (a[0] != '-' && !elf) elf = a;
		else {
			fprintf(stderr, "simuno: bad argument '%s'\n", a);
			usage(stderr);
			return 2;
		}
	}
	if (!elf || !link_path || freq == 0 || boot_delay_ms < 0) {
		usage(stderr);
		return 2;
	}

	/* Keep stdout for our READY line only: libsimavr and uart_pty printf()
	 * chatter ("Starting atmega328p", "UART-0 configured ...") to stdout. */
	fflush(stdout);
	int ready_fd = dup(STDOUT_FILENO);
	if (ready_fd < 0 || dup2(STDERR_FILENO, STDOUT_FILENO) < 0) {
		perror("simuno: dup");
		return 1;
	}
	FILE *ready = fdopen(ready_fd, "w");
	setvbuf(stdout, NULL, _IOLBF, 0);

	struct sigaction sa;
	memset(&sa, 0, sizeof(sa));
	sigemptyset(&sa.sa_mask);
	sa.sa_handler = on_stop; /* no SA_RESTART: interrupt nanosleep/select */
	sigaction(SIGTERM, &sa, NULL);
	sigaction(SIGINT, &sa, NULL);
	sigaction(SIGHUP, &sa, NULL);
	sa.sa_handler = on_reset;
	sigaction(SIGUSR1, &sa, NULL);
	sa.sa_handler = on_button;
	sigaction(SIGUSR2, &sa, NULL);
	signal(SIGPIPE, SIG_IGN);

	if (access(elf, R_OK) != 0) {
		fprintf(stderr, "simuno: cannot read %s: %s\n", elf, strerror(errno));
		return 1;
	}
	elf_firmware_t fw;
	memset(&fw, 0, sizeof(fw));
	if (elf_read_firmware(elf, &fw) != 0) {
		fprintf(stderr, "simuno: cannot load ELF %s\n", elf);
		return 1;
	}
	/* Arduino ELFs carry no .mmcu section: the command line decides. */
	snprintf(fw.mmcu, sizeof(fw.mmcu), "%s", mcu);
	fw.frequency = (uint32_t)freq;

	avr_t *avr = avr_make_mcu_by_name(fw.mmcu);
	if (!avr) {
		fprintf(stderr, "simuno: unknown MCU '%s'\n", fw.mmcu);
		return 1;
	}
	avr_init(avr);
	avr_load_firmware(avr, &fw);
	avr->frequency = (uint32_t)freq;
	avr->sleep = sleep_noop;

	if (log_path) {
		cycles_log = fopen(log_path, "a");
		if (!cycles_log) {
			fprintf(stderr, "simuno: cannot open %s: %s\n", log_path, strerror(errno));
			return 1;
		}
		avr_register_io_write(avr, GPIOR0_DATA_ADDR, gpior0_write_hook, NULL);
	}

	/* uart_pty creates the pty (raw mode, no echo: cfmakeraw on the master)
	 * and a thread moving bytes between the pty and two fifos. In Debian's
	 * simavr 1.6 the thread never touches the AVR: bytes reach the UART from
	 * the simulation thread (XON hook plus a 1 kHz cycle timer), so no lock
	 * is needed around avr_run(). uart_pty_connect() also points the shared
	 * /tmp/simavr-uart0 at our pty; we never use that link (several simuno
	 * instances may run side by side) and remove it at exit if still ours. */
	static uart_pty_t pty;
	uart_pty_init(avr, &pty);
	if (!pty.port[0].s || !pty.port[0].slavename[0]) {
		fprintf(stderr, "simuno: uart_pty_init failed\n");
		return 1;
	}
	snprintf(slave_name, sizeof(slave_name), "%s", pty.port[0].slavename);
	pty_master = pty.port[0].s;
	uart_pty_connect(&pty, '0');
	{
		/* belt and braces: raw, no echo, no signals, 8N1 */
		struct termios tio;
		if (tcgetattr(pty_master, &tio) == 0) {
			cfmakeraw(&tio);
			tcsetattr(pty_master, TCSANOW, &tio);
		}
	}

	/* uart_pty_connect() cleared the STDIO echo; also drop POLL_SLEEP, the
	 * usleep(1) simavr does on every idle UCSRnA read, which would make
	 * the simulation far slower than real time. We throttle ourselves. */
	uint32_t flags = 0;
	avr_ioctl(avr, AVR_IOCTL_UART_GET_FLAGS('0'), &flags);
	flags &= ~(AVR_UART_FLAG_STDIO | AVR_UART_FLAG_POOL_SLEEP);
	avr_ioctl(avr, AVR_IOCTL_UART_SET_FLAGS('0'), &flags);
	avr_irq_t *uart_xoff = avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XOFF);
	if (!uart_xoff) {
		fprintf(stderr, "simuno: MCU '%s' has no UART0\n", fw.mmcu);
		return 1;
	}

	/* Opening the port resets a real Uno (DTR pulses the reset line). A pty has
	 * no DTR, but the kernel reports every open() of the slave to inotify. */
	int open_watch = -1;
	if (reset_on_open) {
		open_watch = inotify_init1(IN_NONBLOCK | IN_CLOEXEC);
		if (open_watch < 0 || inotify_add_watch(open_watch, slave_name, IN_OPEN) < 0) {
			fprintf(stderr, "simuno: --reset-on-open: inotify on %s: %s\n", slave_name, strerror(errno));
			return 1;
		}
	}

	/* --link PATH -> /dev/pts/N */
	{
		struct stat st;
		if (lstat(link_path, &st) == 0) {
			if (!S_ISLNK(st.st_mode)) {
				fprintf(stderr, "simuno: %s exists and is not a symlink\n", link_path);
				return 1;
			}
			unlink(link_path);
		}
		if (symlink(slave_name, link_path) != 0) {
			fprintf(stderr, "simuno: cannot create symlink %s: %s\n", link_path, strerror(errno));
			return 1;
		}
	}
	fprintf(stderr, "simuno: %s on %s (%s @ %lu Hz%s), link %s\n", elf, slave_name,
		fw.mmcu, freq, fast ? ", unthrottled" : "", link_path);

	/* simavr models no pull-ups: drive PD2 as a pulled-up pin with a button to ground would. */
	avr_irq_t *button = avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('D'), 2);
	if (watch)
		watch_pins(avr);
	int button_level = -1;

	int64_t base_wall = now_ns();
	avr_cycle_count_t base_cycle = avr->cycle;
	int64_t hold_until = 0; /* wall time until which the MCU is held in reset */
	int announced = 0, state = cpu_Running, rc = 0;

	while (!g_stop) {
		if (open_watch >= 0) {
			char evbuf[4096] __attribute__((aligned(__alignof__(struct inotify_event))));
			ssize_t n = read(open_watch, evbuf, sizeof(evbuf));
			if (n > 0) {
				fprintf(stderr, "simuno: pty opened\n");
				g_reset = 1;
			}
		}
		if (g_reset) {
			g_reset = 0;
			avr_reset(avr);
			button_level = -1; /* the reset cleared the pin registers: drive the button again */
			discard_input(&pty);
			/* XOFF is a filtered irq (notifies on change only) and the UART
			 * fifo was just emptied behind its back: resync it. */
			avr_raise_irq(uart_xoff, 0);
			fprintf(stderr, "simuno: reset\n");
			hold_until = boot_delay_ms ? now_ns() + boot_delay_ms * 1000000LL : 0;
		}
		int want_level = (g_button_toggles % 2) ? 0 : 1;
		if (button && want_level != button_level) {
			/* the level an input pin reads when nothing drives it, then the pin itself */
			avr_ioport_external_t ext = { .name = 'D', .mask = 1 << 2, .value = (unsigned)want_level << 2 };
			avr_ioctl(avr, AVR_IOCTL_IOPORT_SET_EXTERNAL('D'), &ext);
			button->value = !want_level; /* the irq filters repeats: make this one count */
			avr_raise_irq(button, want_level);
			button_level = want_level;
		}
		if (hold_until) {
			if (now_ns() < hold_until) {
				discard_input(&pty); /* the bootloader eats them */
				struct timespec ts = { 0, 1000000 };
				nanosleep(&ts, NULL);
				continue;
			}
			hold_until = 0;
			base_wall = now_ns();
			base_cycle = avr->cycle;
		}

		for (int i = 0; i < RUN_BATCH; i++) {
			state = avr_run(avr);
			if (state == cpu_Done || state == cpu_Crashed)
				break;
		}
		if (state == cpu_Done || state == cpu_Crashed) {
			fprintf(stderr, "simuno: firmware %s at cycle %llu\n",
				state == cpu_Done ? "stopped" : "crashed",
				(unsigned long long)avr->cycle);
			rc = state == cpu_Done ? 0 : 1;
			if (!announced) {
				fprintf(ready, "READY %s\n", link_path);
				fflush(ready);
			}
			break;
		}
		if (!announced) {
			announced = 1;
			fprintf(ready, "READY %s\n", link_path);
			fflush(ready);
		}

		if (!fast) {
			int64_t sim = (int64_t)((avr->cycle - base_cycle) * 1000000000ULL / freq);
			int64_t wall = now_ns() - base_wall;
			if (sim - wall > 1000000) { /* ahead by > 1 ms: wait */
				int64_t d = sim - wall;
				struct timespec ts = { (time_t)(d / 1000000000LL), (long)(d % 1000000000LL) };
				nanosleep(&ts, NULL);
			} else if (wall - sim > MAX_LAG_NS) { /* host too slow: don't race */
				base_wall = now_ns();
				base_cycle = avr->cycle;
			}
		}
	}

	remove_link_if_ours(link_path);
	remove_link_if_ours("/tmp/simavr-uart0");
	if (cycles_log)
		fclose(cycles_log);
	fflush(stdout);
	fflush(stderr);
	/* Not uart_pty_stop(): its thread may be blocked writing to a pty nobody
	 * reads, and joining it would hang. Process exit ends it. */
	_exit(rc);
}
