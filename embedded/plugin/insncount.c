/*
 * QEMU TCG plugin: counts the guest instructions a run executes (single vCPU).
 *
 * For targets without a usable instruction counter in QEMU (Cortex-M: no PMU, no DWT).
 * Prints "insns: N" when the guest exits. With the argument mark=ADDR (hex), it also prints
 * "mark: N" (the running count) each time the instruction at ADDR executes; the program calls
 * a marker function right before and right after each frame, so consecutive marks bracket a
 * frame. The count advances a whole translation block at a time, so a mark is exact to within
 * the instructions of the block it sits in (a handful, the same every time).
 *
 * The few API declarations needed are written out here (Debian ships no qemu-plugin.h).
 * Build: gcc -shared -fPIC -O2 -o libinsncount.so insncount.c
 * Use:   qemu-system-arm ... -plugin ./libinsncount.so,mark=0x1234 -d plugin -D log.txt
 */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef uint64_t qemu_plugin_id_t;
struct qemu_plugin_tb;
struct qemu_plugin_insn;
typedef struct qemu_info_t qemu_info_t; /* only passed through */
typedef void (*vcpu_udata_cb)(unsigned int vcpu_index, void *userdata);
enum { CB_NO_REGS = 0 };

void qemu_plugin_register_vcpu_tb_trans_cb(qemu_plugin_id_t id,
                                           void (*cb)(qemu_plugin_id_t, struct qemu_plugin_tb *));
void qemu_plugin_register_vcpu_tb_exec_cb(struct qemu_plugin_tb *tb, vcpu_udata_cb cb, int flags,
                                          void *userdata);
void qemu_plugin_register_vcpu_insn_exec_cb(struct qemu_plugin_insn *insn, vcpu_udata_cb cb,
                                            int flags, void *userdata);
size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb *tb);
struct qemu_plugin_insn *qemu_plugin_tb_get_insn(const struct qemu_plugin_tb *tb, size_t idx);
uint64_t qemu_plugin_insn_vaddr(const struct qemu_plugin_insn *insn);
void qemu_plugin_register_atexit_cb(qemu_plugin_id_t id, void (*cb)(qemu_plugin_id_t, void *),
                                    void *userdata);
void qemu_plugin_outs(const char *string);

__attribute__((visibility("default"))) int qemu_plugin_version = 2;

static uint64_t executed;
static uint64_t mark_addr;
static int have_mark;

static void on_tb(unsigned int vcpu, void *n) {
    (void)vcpu;
    executed += (uintptr_t)n;
}

static void on_mark(unsigned int vcpu, void *unused) {
    char line[64];
    (void)vcpu;
    (void)unused;
    snprintf(line, sizeof line, "mark: %llu\n", (unsigned long long)executed);
    qemu_plugin_outs(line);
}

static void on_translate(qemu_plugin_id_t id, struct qemu_plugin_tb *tb) {
    size_t n = qemu_plugin_tb_n_insns(tb);
    (void)id;
    qemu_plugin_register_vcpu_tb_exec_cb(tb, on_tb, CB_NO_REGS, (void *)(uintptr_t)n);
    if (!have_mark)
        return;
    for (size_t i = 0; i < n; i++) {
        struct qemu_plugin_insn *insn = qemu_plugin_tb_get_insn(tb, i);
        if (qemu_plugin_insn_vaddr(insn) == mark_addr)
            qemu_plugin_register_vcpu_insn_exec_cb(insn, on_mark, CB_NO_REGS, NULL);
    }
}

static void on_atexit(qemu_plugin_id_t id, void *unused) {
    char line[64];
    (void)id;
    (void)unused;
    snprintf(line, sizeof line, "insns: %llu\n", (unsigned long long)executed);
    qemu_plugin_outs(line);
}

__attribute__((visibility("default"))) int qemu_plugin_install(qemu_plugin_id_t id,
                                                               const qemu_info_t *info, int argc,
                                                               char **argv) {
    (void)info;
    for (int i = 0; i < argc; i++) {
        if (strncmp(argv[i], "mark=", 5) == 0) {
            /* Thumb symbols carry bit 0; instruction addresses do not. */
            mark_addr = strtoull(argv[i] + 5, NULL, 16) & ~(uint64_t)1;
            have_mark = 1;
        }
    }
    qemu_plugin_register_vcpu_tb_trans_cb(id, on_translate);
    qemu_plugin_register_atexit_cb(id, on_atexit, NULL);
    return 0;
}
