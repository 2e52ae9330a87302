/* SPDX-License-Identifier: Apache-2.0
 * sim_soak_c_reader NAME: the soak's reader through the C API (sim/sim.h), SIM_waitData and
 * SIM_readData, as a C program would use them. Checks every frame it gets: whole (the pattern of
 * tests/soak/soak_frames.hpp, or a whole number of finite LiDAR points), never out of order, and
 * counts checksum failures as torn. One JSON line per second; SIGTERM ends it with exit 0. */
#include <math.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "sim/sim.h"

#define MAGIC 0x314B414F534D4953ull
#define VIDEO_TAG 0x5649444500000000ull
#define HEADER_WORDS 11u

static volatile sig_atomic_t stop_requested = 0;
static void on_stop(int sig) {
  (void)sig;
  stop_requested = 1;
}

static uint64_t mix(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}
static uint64_t pattern_word(uint64_t tag, uint64_t index) {
  if ((tag & ~0xFFull) == VIDEO_TAG) return 0x0101010101010101ull * (0x10 + 0x1F * (tag & 0x7));
  return mix(index + 0x9E3779B97F4A7C15ull) ^ mix(tag ^ 0xD1B54A32D192ED03ull);
}
static uint64_t word_at(const unsigned char *frame, size_t index) {
  uint64_t w;
  memcpy(&w, frame + index * 8, 8);
  return w;
}

/* 1 when the frame is whole (see soak_frames.hpp: verify and verify_points). */
static int whole(const unsigned char *frame, size_t size) {
  size_t words = size / 8, i;
  if (size >= 8 && word_at(frame, 0) == MAGIC) {
    uint64_t tag;
    if (size % 8 != 0 || words < HEADER_WORDS) return 0;
    tag = word_at(frame, 1);
    for (i = HEADER_WORDS; i < words; i += 64) {
      if (word_at(frame, i) != pattern_word(tag, i)) return 0;
    }
    return word_at(frame, words - 1) == pattern_word(tag, words - 1);
  }
  if (size % 24 != 0) return 0; /* LiDAR points of the pcap replay */
  for (i = 0; i < size; i += 24 * 7) {
    float xyz[3];
    int k;
    memcpy(xyz, frame + i, sizeof xyz);
    for (k = 0; k < 3; ++k) {
      if (!isfinite(xyz[k]) || fabsf(xyz[k]) > 1000.0f) return 0;
    }
  }
  return 1;
}

struct counters {
  unsigned long long frames, torn, out_of_order, opens;
};

static void print_stats(const char *name, const struct counters *c, int final) {
  printf("{\"kind\":\"stats\",\"role\":\"c\",\"final\":%s,\"streams\":{\"%s\":{\"frames\":%llu,"
         "\"torn\":%llu,\"out_of_order\":%llu,\"opens\":%llu}}}\n",
         final ? "true" : "false", name, c->frames, c->torn, c->out_of_order, c->opens);
  fflush(stdout);
}

static void violation(const char *what, const char *name, unsigned long long seq) {
  printf("{\"kind\":\"violation\",\"what\":\"%s\",\"stream\":\"%s\",\"seq\":%llu}\n", what, name, seq);
  fflush(stdout);
}

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + ts.tv_nsec / 1e9;
}

/* Reads until the stream stays without a writer for 2 s (then the caller reopens it by name). */
static void read_until_gone(sim_reader *r, const char *name, struct counters *c, unsigned char **buf,
                            size_t *capacity, double *next_print) {
  unsigned long long last_seq = 0;
  long long last_publish = 0;
  double gone_since = 0;
  while (!stop_requested) {
    sim_frame_info info;
    long long n;
    int w = SIM_waitData(r, 1000);
    if (now_s() >= *next_print) {
      print_stats(name, c, 0);
      *next_print += 1.0;
    }
    if (w == 0) continue;
    n = w == 1 ? SIM_readData(r, *buf, *capacity, &info) : w;
    if (n == SIM_EBUFFER) { /* the stream was replaced by a larger layout */
      *capacity *= 2;
      *buf = realloc(*buf, *capacity);
      continue;
    }
    if (n == SIM_ECHECKSUM) { ++c->torn; violation("torn", name, 0); continue; }
    if (n == SIM_EWRITERGONE || n == SIM_ESTALE || n == SIM_EREGION) {
      if (gone_since == 0) gone_since = now_s();
      if (n == SIM_EREGION || now_s() - gone_since > 2.0) return;
      { struct timespec pause = {0, 50000000}; nanosleep(&pause, NULL); }
      continue;
    }
    gone_since = 0;
    if (n < 0 || info.seq == 0) continue;
    ++c->frames;
    if (!whole(*buf, (size_t)n)) { ++c->torn; violation("torn", name, info.seq); }
    /* Not above the previous number is out of order, unless published later: a stream removed
     * and created anew numbers from 1 again (a replacing region carries the numbering on). */
    if (last_seq != 0 && info.seq <= last_seq && info.publish_ns <= last_publish) {
      ++c->out_of_order;
      violation("out_of_order", name, info.seq);
    }
    last_seq = info.seq;
    last_publish = info.publish_ns;
  }
}

int main(int argc, char **argv) {
  struct counters c = {0, 0, 0, 0};
  size_t capacity = 8u << 20;
  unsigned char *buf = malloc(capacity);
  double next_print = now_s() + 1.0;
  struct sigaction action;
  if (argc != 2) {
    fprintf(stderr, "usage: sim_soak_c_reader NAME\n");
    return 2;
  }
  memset(&action, 0, sizeof action);
  action.sa_handler = on_stop;
  sigaction(SIGTERM, &action, NULL);
  sigaction(SIGINT, &action, NULL);
  while (!stop_requested) {
    sim_reader *r = SIM_readerInit(argv[1], 0);
    if (!r) { /* no stream now (its writer was killed and the stream removed): look again */
      struct timespec pause = {0, 20000000};
      nanosleep(&pause, NULL);
      if (now_s() >= next_print) {
        print_stats(argv[1], &c, 0);
        next_print += 1.0;
      }
      continue;
    }
    ++c.opens;
    read_until_gone(r, argv[1], &c, &buf, &capacity, &next_print);
    SIM_readerClose(r);
  }
  print_stats(argv[1], &c, 1);
  free(buf);
  return 0;
}
