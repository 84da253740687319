/* Model-description text helpers shared by the FMI 2.0 host (host.c, fuzz.c) and the FMI 3.0
 * host (fmi3/): they read the XML as text and take attributes from it, independently of either
 * version's headers. */
#ifndef BISTABLE_MD_TEXT_H
#define BISTABLE_MD_TEXT_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The whole file at `path` as a NUL-terminated string (malloc'd), or NULL. */
static inline char *read_text(const char *path) {
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *s = malloc((size_t)n + 1);
    if (s && fread(s, 1, (size_t)n, f) != (size_t)n) n = 0;
    if (s) s[n] = 0;
    fclose(f);
    return s;
}

/* Copies the value of attribute `key` found in [p, end) into buf; 0 if absent. */
static inline int attr(const char *p, const char *end, const char *key, char *buf, size_t n) {
    char pat[64];
    snprintf(pat, sizeof pat, " %s=\"", key);
    const char *q = strstr(p, pat);
    if (!q || q >= end) return 0;
    q += strlen(pat);
    size_t k = 0;
    while (q < end && *q != '"' && k + 1 < n) buf[k++] = *q++;
    buf[k] = 0;
    return 1;
}

#endif
