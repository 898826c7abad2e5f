/* handwritten_pr.h: the hand-written PR AHEAD plan (bench/c_ahead/handwritten_pr.c). */
#ifndef HANDWRITTEN_PR_H
#define HANDWRITTEN_PR_H

#include <stdint.h>

#include "submarine.h"

void hand_pr_init(void);
/* One step of PR: pre, new command, AHEAD state table, write status and TB command. */
void hand_pr_step(submarine_buffers *G, uint64_t cycle);

#endif /* HANDWRITTEN_PR_H */
