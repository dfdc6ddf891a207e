/* Checks a YAML scene file before PETSc reads it (-options_file_yaml).

   PETSc parses the file inside PetscInitialize: malformed YAML ends there in a traceback without a line
   number, a NUL byte silently cuts the file short, binary garbage may be taken as an empty file, and a
   misspelt section surfaces later as an unrelated error. This check walks the file with libyaml's event
   parser first and names the first problem as "FILE:LINE:COLUMN: problem" (1-based), so the driver can
   print one line and stop before PETSc starts.

   What it accepts is what PETSc's loader turns into options, restricted to the shape of our scenes: one
   document whose top level is a mapping; keys are scalars; values are scalars, mappings (a section whose
   keys get the prefix "<key>_"), at most PFF_YAML_MAX_DEPTH mappings deep, or lists of scalars (PETSc
   joins them with commas); no anchors, aliases or merge keys; every top-level key is a known section or
   option (PffYAMLNames). Keys inside sections are left to PffOptionsCheckUnused().

   Plain C and libyaml: it runs before PetscInitialize, so it cannot use PETSc's allocator or errors. */
#include <pff.h>
#include <yaml.h>
#include <ctype.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define PFF_YAML_MAX_DEPTH 8          /* mappings; our scenes use 2, PETSc's prefix stack holds 25 */
#define PFF_YAML_MAX_BYTES (16 << 20) /* a scene is a few kB; anything this large is not one */

typedef enum {
  PFF_YAML_SECTION, /* "name" or a flattened "name_..." (grid, grid_h) */
  PFF_YAML_KEY,     /* exactly "name" */
  PFF_YAML_REGION   /* "name_N" or "name_N_..." with N a number (liquid_0, liquid_0_type) */
} PffYAMLNameKind;

/* The top-level keys a scene file may hold: the option prefixes and top-level options read in src/ and
   used in config/, and the PETSc options users put in scene files. */
static const struct {
  const char     *name;
  PffYAMLNameKind kind;
} PffYAMLNames[] = {
    /* pfflip sections (option prefixes) */
    {"grid", PFF_YAML_SECTION},
    {"sim", PFF_YAML_SECTION},
    {"flow", PFF_YAML_SECTION},
    {"pressure", PFF_YAML_SECTION},
    {"pffmg", PFF_YAML_SECTION},
    {"particles", PFF_YAML_SECTION},
    {"partition", PFF_YAML_SECTION},
    {"fluid", PFF_YAML_SECTION},
    {"adapt", PFF_YAML_SECTION},
    {"tall", PFF_YAML_SECTION},
    {"demo", PFF_YAML_SECTION},
    {"rt", PFF_YAML_SECTION},
    {"still", PFF_YAML_SECTION},
    {"shear", PFF_YAML_SECTION},
    {"bench", PFF_YAML_SECTION},
    /* pfflip top-level options */
    {"scene", PFF_YAML_KEY},
    {"output_dir", PFF_YAML_KEY},
    {"rho_liquid", PFF_YAML_KEY},
    {"rho_gas", PFF_YAML_KEY},
    {"nu_liquid", PFF_YAML_KEY},
    {"nu_gas", PFF_YAML_KEY},
    {"gravity", PFF_YAML_KEY},
    {"liquid", PFF_YAML_REGION},
    {"gas", PFF_YAML_REGION},
    {"solid", PFF_YAML_REGION},
    {"body", PFF_YAML_REGION},
    /* PETSc */
    {"ksp", PFF_YAML_SECTION},
    {"pc", PFF_YAML_SECTION},
    {"mg", PFF_YAML_SECTION},
    {"log", PFF_YAML_SECTION},
    {"malloc", PFF_YAML_SECTION},
    {"help", PFF_YAML_KEY},
    {"version", PFF_YAML_KEY},
    {"info", PFF_YAML_KEY},
    {"options_left", PFF_YAML_KEY},
    {"options_view", PFF_YAML_KEY},
    {"options_monitor", PFF_YAML_KEY},
    {"memory_view", PFF_YAML_KEY},
    {"on_error_abort", PFF_YAML_KEY},
    {"fp_trap", PFF_YAML_KEY},
};

static int PffYAMLIsKnownName(const char *key)
{
  for (size_t i = 0; i < sizeof(PffYAMLNames) / sizeof(PffYAMLNames[0]); i++) {
    const char *name = PffYAMLNames[i].name;
    size_t      n    = strlen(name);
    if (strncmp(key, name, n)) continue;
    switch (PffYAMLNames[i].kind) {
    case PFF_YAML_KEY:
      if (!key[n]) return 1;
      break;
    case PFF_YAML_SECTION:
      if (!key[n] || key[n] == '_') return 1;
      break;
    case PFF_YAML_REGION: {
      const char *p = key + n;
      if (*p++ != '_' || !isdigit((unsigned char)*p)) break;
      while (isdigit((unsigned char)*p)) p++;
      if (!*p || *p == '_') return 1;
    } break;
    }
  }
  return 0;
}

const char *PffFileProblem(const char path[])
{
  struct stat st;
  if (stat(path, &st) || access(path, R_OK)) return "no such file or not readable";
  if (S_ISDIR(st.st_mode)) return "is a directory";
  if (!S_ISREG(st.st_mode)) return "is not a regular file";
  return NULL;
}

typedef struct {
  const char          *path;
  const unsigned char *buf; /* the file's bytes */
  size_t               n;
  char                *msg;
  size_t               len;
} PffYAMLCheck;

/* Writes "path:line:column: problem" (or "path: problem" for line 0) into the message; returns 1. */
static int PffYAMLFail(PffYAMLCheck *c, size_t line, size_t column, const char *fmt, ...)
{
  char    problem[512];
  va_list ap;

  va_start(ap, fmt);
  vsnprintf(problem, sizeof(problem), fmt, ap);
  va_end(ap);
  if (line)
    snprintf(c->msg, c->len, "%s:%zu:%zu: %s", c->path, line, column, problem);
  else
    snprintf(c->msg, c->len, "%s: %s", c->path, problem);
  return 1;
}

/* The length in bytes of the line break at buf[i] (\r\n, \r, \n, and in UTF-8 NEL, LS, PS, as libyaml counts
   lines), or 0. */
static size_t PffYAMLBreakLength(const PffYAMLCheck *c, size_t i)
{
  const unsigned char *b = c->buf + i;
  size_t               r = c->n - i;
  if (b[0] == '\n') return 1;
  if (b[0] == '\r') return r > 1 && b[1] == '\n' ? 2 : 1;
  if (r > 1 && b[0] == 0xC2 && b[1] == 0x85) return 2;
  if (r > 2 && b[0] == 0xE2 && b[1] == 0x80 && (b[2] == 0xA8 || b[2] == 0xA9)) return 3;
  return 0;
}

/* 1-based line and column of a byte offset; columns count characters (UTF-8 lead bytes), as libyaml's
   marks do. */
static void PffYAMLOffsetToPosition(const PffYAMLCheck *c, size_t offset, size_t *line, size_t *column)
{
  *line   = 1;
  *column = 1;
  for (size_t i = 0; i < offset && i < c->n;) {
    size_t br = PffYAMLBreakLength(c, i);
    if (br) {
      (*line)++;
      *column = 1;
      i += br;
    } else if ((c->buf[i++] & 0xC0) != 0x80)
      (*column)++;
  }
}

/* The byte at a libyaml mark (0-based line and column), or -1 past the end. */
static int PffYAMLByteAt(const PffYAMLCheck *c, yaml_mark_t mark)
{
  size_t i = 0, line = 0, column = 0;
  while (i < c->n && line < mark.line) {
    size_t br = PffYAMLBreakLength(c, i);
    if (br) line++;
    i += br ? br : 1;
  }
  for (; i < c->n && column < mark.column; i++)
    if ((c->buf[i] & 0xC0) != 0x80) column++;
  while (i < c->n && (c->buf[i] & 0xC0) == 0x80) i++;
  return i < c->n ? c->buf[i] : -1;
}

/* libyaml's own error: the reader (encoding), the scanner (tokens) or the parser (structure). */
static int PffYAMLFailParser(PffYAMLCheck *c, const yaml_parser_t *p)
{
  size_t line, column;

  switch (p->error) {
  case YAML_READER_ERROR:
    PffYAMLOffsetToPosition(c, p->problem_offset, &line, &column);
    if (p->problem_value >= 0)
      return PffYAMLFail(c, line, column, "not UTF-8 YAML text: %s (0x%02X)", p->problem, (unsigned)p->problem_value);
    return PffYAMLFail(c, line, column, "not UTF-8 YAML text: %s", p->problem);
  case YAML_SCANNER_ERROR:
  case YAML_PARSER_ERROR: {
    const char *problem = p->problem ? p->problem : "malformed YAML";
    line                = p->problem_mark.line + 1;
    column              = p->problem_mark.column + 1;
    if (p->error == YAML_SCANNER_ERROR && PffYAMLByteAt(c, p->problem_mark) == '\t')
      return PffYAMLFail(c, line, column, "a tab character where YAML expects a token (indent with spaces)");
    if (p->context && strlen(p->context) < 64)
      return PffYAMLFail(c, line, column, "%s (%s at %zu:%zu)", problem, p->context, (size_t)p->context_mark.line + 1,
                         (size_t)p->context_mark.column + 1);
    return PffYAMLFail(c, line, column, "%s", problem);
  }
  case YAML_MEMORY_ERROR:
    return PffYAMLFail(c, 0, 0, "out of memory while parsing");
  default:
    return PffYAMLFail(c, 0, 0, "malformed YAML (%s)", p->problem ? p->problem : "libyaml error");
  }
}

/* A key for a message: at most 40 characters, anything but printable ASCII shown as '?'. */
static void PffYAMLQuoteKey(const char *key, char out[64])
{
  size_t i = 0;
  for (; key[i] && i < 40; i++) out[i] = key[i] >= 0x20 && key[i] < 0x7f ? key[i] : '?';
  if (key[i]) {
    memcpy(out + i, "...", 3);
    i += 3;
  }
  out[i] = '\0';
}

typedef struct {
  int  mapping;   /* 1 mapping, 0 sequence */
  int  expectKey; /* mapping: the next node is a key */
  char key[96];   /* mapping: the key of the pair being read */
} PffYAMLFrame;

#define PFF_YAML_MAX_KEYS 1024

/* The options a file sets, as PETSc flattens them (section_key): a second one would silently win. */
typedef struct {
  char   name[PFF_YAML_MAX_KEYS][160];
  size_t line[PFF_YAML_MAX_KEYS];
  int    n;
} PffYAMLKeys;

/* Records the option the pair at the top of the stack sets; returns the line of an earlier one, or 0. */
static size_t PffYAMLAddKey(PffYAMLKeys *keys, const PffYAMLFrame *stack, int depth, size_t line, char name[160])
{
  name[0] = 0;
  for (int d = 0; d < depth; d++) {
    if (!stack[d].mapping) return 0;
    if (d) strncat(name, "_", 159 - strlen(name));
    strncat(name, stack[d].key, 159 - strlen(name));
  }
  for (int i = 0; i < keys->n; i++)
    if (!strcmp(keys->name[i], name)) return keys->line[i];
  if (keys->n < PFF_YAML_MAX_KEYS) {
    memcpy(keys->name[keys->n], name, 160);
    keys->line[keys->n++] = line;
  }
  return 0;
}

/* Walks the events of the file; returns 0 for an acceptable scene, else 1 with the message set. */
static int PffYAMLCheckEvents(PffYAMLCheck *c, yaml_parser_t *parser)
{
  PffYAMLFrame stack[PFF_YAML_MAX_DEPTH + 1];
  int          depth = 0, mappings = 0, documents = 0, done = 0, bad = 0;
  PffYAMLKeys *keys = calloc(1, sizeof(*keys));
  char         name[160];
  size_t       first;

  if (!keys) return PffYAMLFail(c, 0, 0, "out of memory");

  while (!done && !bad) {
    yaml_event_t  e;
    PffYAMLFrame *top;
    const char   *anchor = NULL, *what;
    size_t        line, column;

    if (!yaml_parser_parse(parser, &e)) {
      bad = PffYAMLFailParser(c, parser);
      break;
    }
    top    = depth ? &stack[depth - 1] : NULL;
    line   = e.start_mark.line + 1;
    column = e.start_mark.column + 1;
    if (e.type == YAML_SCALAR_EVENT) anchor = (const char *)e.data.scalar.anchor;
    if (e.type == YAML_SEQUENCE_START_EVENT) anchor = (const char *)e.data.sequence_start.anchor;
    if (e.type == YAML_MAPPING_START_EVENT) anchor = (const char *)e.data.mapping_start.anchor;
    if (anchor) {
      bad = PffYAMLFail(c, line, column, "anchors (&%.40s) and aliases are not supported", anchor);
      yaml_event_delete(&e);
      break;
    }
    switch (e.type) {
    case YAML_STREAM_END_EVENT:
      done = 1;
      if (!documents) bad = PffYAMLFail(c, 0, 0, "the file is empty");
      break;
    case YAML_DOCUMENT_START_EVENT:
      if (++documents > 1) bad = PffYAMLFail(c, line, column, "more than one YAML document (one scene per file)");
      break;
    case YAML_ALIAS_EVENT:
      bad = PffYAMLFail(c, line, column, "aliases are not supported (*%.40s)", (const char *)e.data.alias.anchor);
      break;
    case YAML_SCALAR_EVENT: {
      const char *value = (const char *)e.data.scalar.value;
      if (!top) {
        if (!value[0] && e.data.scalar.plain_implicit)
          bad = PffYAMLFail(c, 0, 0, "the file is empty");
        else
          bad = PffYAMLFail(c, line, column, "the top level is a scalar; a scene is a mapping of keys (name: value)");
      } else if (top->mapping && top->expectKey) {
        char quoted[64];
        top->expectKey = 0;
        snprintf(top->key, sizeof(top->key), "%s", value);
        if (!strcmp(value, "<<"))
          bad = PffYAMLFail(c, line, column, "merge keys (<<) are not supported");
        else if (depth == 1 && !PffYAMLIsKnownName(value)) {
          PffYAMLQuoteKey(value, quoted);
          bad = PffYAMLFail(c, line, column, "unknown section or key \"%s\" (misspelt?)", quoted);
        }
      } else if (top->mapping) {
        top->expectKey = 1;
        if ((first = PffYAMLAddKey(keys, stack, depth, line, name)))
          bad =
              PffYAMLFail(c, line, column, "%s is set twice (first at line %zu); one would silently win", name, first);
      }
    } break;
    case YAML_SEQUENCE_START_EVENT:
    case YAML_MAPPING_START_EVENT:
      what = e.type == YAML_SEQUENCE_START_EVENT ? "list" : "mapping";
      if (!top && e.type == YAML_SEQUENCE_START_EVENT)
        bad = PffYAMLFail(c, line, column, "the top level is a list; a scene is a mapping of keys (name: value)");
      else if (top && !top->mapping)
        bad =
            PffYAMLFail(c, line, column, "a %s inside a list; a list may hold only scalars (joined with commas)", what);
      else if (top && top->expectKey)
        bad = PffYAMLFail(c, line, column, "a key is a %s; keys must be names", what);
      else if (e.type == YAML_MAPPING_START_EVENT && ++mappings > PFF_YAML_MAX_DEPTH)
        bad = PffYAMLFail(c, line, column, "mappings nested deeper than %d levels", PFF_YAML_MAX_DEPTH);
      else if (top && e.type == YAML_SEQUENCE_START_EVENT && (first = PffYAMLAddKey(keys, stack, depth, line, name)))
        bad = PffYAMLFail(c, line, column, "%s is set twice (first at line %zu); one would silently win", name, first);
      else {
        if (top) top->expectKey = 1; /* for the key after this value */
        stack[depth].mapping   = e.type == YAML_MAPPING_START_EVENT;
        stack[depth].expectKey = 1;
        depth++;
      }
      break;
    case YAML_SEQUENCE_END_EVENT:
    case YAML_MAPPING_END_EVENT:
      if (e.type == YAML_MAPPING_END_EVENT) mappings--;
      depth--;
      break;
    default:
      break;
    }
    yaml_event_delete(&e);
  }
  free(keys);
  return bad;
}

int PffYAMLCheckFile(const char path[], char msg[], size_t len)
{
  PffYAMLCheck   c = {path, NULL, 0, msg, len};
  struct stat    st;
  FILE          *fp;
  unsigned char *buf;
  const void    *nul;
  yaml_parser_t  parser;
  int            bad;

  const char *problem = PffFileProblem(path);

  if (problem || stat(path, &st)) return PffYAMLFail(&c, 0, 0, "%s", problem ? problem : "cannot be read");
  if (st.st_size > PFF_YAML_MAX_BYTES)
    return PffYAMLFail(&c, 0, 0, "is too large for a scene file (%lld bytes, at most %d)", (long long)st.st_size,
                       PFF_YAML_MAX_BYTES);
  if (st.st_size == 0) return PffYAMLFail(&c, 0, 0, "the file is empty");
  fp = fopen(path, "rb");
  if (!fp) return PffYAMLFail(&c, 0, 0, "no such file or not readable");
  buf = malloc((size_t)st.st_size); /* PETSc is not initialized yet */
  if (!buf) {
    fclose(fp);
    return PffYAMLFail(&c, 0, 0, "out of memory reading the file");
  }
  c.n   = fread(buf, 1, (size_t)st.st_size, fp);
  c.buf = buf;
  bad   = ferror(fp);
  fclose(fp);
  if (bad)
    bad = PffYAMLFail(&c, 0, 0, "cannot be read");
  else if (c.n == 0)
    bad = PffYAMLFail(&c, 0, 0, "the file is empty");
  else if ((nul = memchr(buf, 0, c.n))) {
    size_t line, column;
    PffYAMLOffsetToPosition(&c, (size_t)((const unsigned char *)nul - buf), &line, &column);
    bad = PffYAMLFail(&c, line, column, "a NUL byte; the file is binary, not YAML text");
  } else if (c.n >= 2 && ((buf[0] == 0xFE && buf[1] == 0xFF) || (buf[0] == 0xFF && buf[1] == 0xFE))) {
    bad = PffYAMLFail(&c, 1, 1, "a UTF-16 byte-order mark; PETSc reads UTF-8 text only");
  } else if (!yaml_parser_initialize(&parser))
    bad = PffYAMLFail(&c, 0, 0, "out of memory starting the YAML parser");
  else {
    yaml_parser_set_input_string(&parser, buf, c.n);
    bad = PffYAMLCheckEvents(&c, &parser);
    yaml_parser_delete(&parser);
  }
  free(buf);
  return bad;
}
