/* SPDX-License-Identifier: Apache-2.0 */
/* The four lines of SIM from C: init a writer, write; init a reader, read.
 * Usage: sim_example_c [/stream_name] */
#include <sim/sim.h>
#include <stdio.h>
#include <string.h>

int main(int argc, char **argv) {
  const char *name = argc > 1 ? argv[1] : "/hello_sim";
  char frame[64] = "a frame in shared memory";
  char buf[64];
  sim_frame_info info;

  sim_writer *w = SIM_writerInit(name, sizeof frame);
  int written = SIM_writeData(w, frame, strlen(frame) + 1);
  sim_reader *r = SIM_readerInit(name, sizeof buf);
  long long n = SIM_readData(r, buf, sizeof buf, &info);

  if (w == NULL || written != 0 || r == NULL || n <= 0) {
    fprintf(stderr, "sim_example_c: %s\n", SIM_lastError());
    return 1;
  }
  printf("read frame %llu: %lld bytes: \"%s\"\n", (unsigned long long)info.seq, n, buf);
  SIM_readerClose(r);
  SIM_writerClose(w);
  return SIM_destroy(name) == 0 && strcmp(buf, frame) == 0 ? 0 : 1;
}
