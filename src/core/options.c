/* Option checks. PETSc's own parsers stop at the first bad character without naming the key, take
   nan and inf as numbers and drop the extra values of a vector; every option of ours goes through
   the strict readers below first, so a bad value is one message of the shape
   "-KEY VALUE is invalid: WHY". Unused options are errors: a misspelt key must not silently fall
   back to a default. */
#include <pff.h>
#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <stdlib.h>

/* Largest magnitude of any real option: far beyond every physical value the scenes use, and small
   enough that squares and products of a few options stay finite in double precision. */
#define PFF_OPTIONS_MAX_REAL 1e12

static const char *PffSkipSpace(const char *s)
{
  while (*s && isspace((unsigned char)*s)) s++;
  return s;
}

/* Parses one real from [s, end): all of it, finite and within the bound; 0 on success, else why. */
static const char *PffParseReal(const char *s, const char *end, PetscReal *v)
{
  char   tok[128], *stop = NULL;
  size_t n;

  s = PffSkipSpace(s);
  while (end > s && isspace((unsigned char)end[-1])) end--;
  n = (size_t)(end - s);
  if (n == 0) return "a number is missing";
  if (n >= sizeof(tok)) return "not a number";
  memcpy(tok, s, n);
  tok[n]   = 0;
  errno    = 0;
  double x = strtod(tok, &stop);
  if (stop == tok || *stop) return "not a number";
  if (!isfinite(x)) return "must be finite";
  if (errno == ERANGE && x != 0) return "must be within +-1e12";
  if (PetscAbsReal((PetscReal)x) > PFF_OPTIONS_MAX_REAL) return "must be within +-1e12";
  *v = (PetscReal)x;
  return NULL;
}

/* Parses one integer from [s, end), all of it; 0 on success, else why. */
static const char *PffParseInt(const char *s, const char *end, PetscInt *v)
{
  char tok[64], *stop = NULL;

  s = PffSkipSpace(s);
  while (end > s && isspace((unsigned char)end[-1])) end--;
  if (end == s) return "an integer is missing";
  if ((size_t)(end - s) >= sizeof(tok)) return "not an integer";
  memcpy(tok, s, (size_t)(end - s));
  tok[end - s] = 0;
  errno        = 0;
  long long x  = strtoll(tok, &stop, 10);
  if (stop == tok || *stop) return "not an integer";
  if (errno == ERANGE || x > PETSC_MAX_INT || x < PETSC_MIN_INT) return "out of the integer range";
  *v = (PetscInt)x;
  return NULL;
}

static const char *PffParseNumber(const char *s, const char *end, PetscBool integer, PetscReal *r, PetscInt *i)
{
  return integer ? PffParseInt(s, end, i) : PffParseReal(s, end, r);
}

/* The raw text of key in options (with prefix) and its name as the user typed it, or has = false. */
static PetscErrorCode PffOptionsRaw(PetscOptions options, const char prefix[], const char key[], char name[],
                                    size_t nlen, char buf[], size_t len, PetscBool *has)
{
  PetscFunctionBeginUser;
  buf[0] = 0;
  PetscCall(PetscSNPrintf(name, nlen, "-%s%s", prefix ? prefix : "", key + 1));
  PetscCall(PetscOptionsGetString(options, prefix, key, buf, len, has));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Reads key, if set, as one real or integer; fails on comm naming the key. */
static PetscErrorCode PffOptionsReadNumber(MPI_Comm comm, PetscOptions options, const char prefix[], const char key[],
                                           PetscBool integer, char name[], size_t nlen, char buf[], size_t len,
                                           PetscBool *has, PetscReal *r, PetscInt *i)
{
  const char *why;

  PetscFunctionBeginUser;
  PetscCall(PffOptionsRaw(options, prefix, key, name, nlen, buf, len, has));
  if (!*has) PetscFunctionReturn(PETSC_SUCCESS);
  why = PffParseNumber(buf, buf + strlen(buf), integer, r, i);
  PetscCheck(!why, comm, PETSC_ERR_ARG_WRONG, "%s %s is invalid: %s", name, buf[0] ? buf : "(no value)", why);
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffOptionsReal_Private(PetscOptionItems *obj, const char key[], const char text[], const char man[],
                                      PetscReal cur, PetscReal *val, PetscBool *set)
{
  char      name[256], buf[256];
  PetscBool has;
  PetscReal v;

  PetscFunctionBeginUser;
  PetscCall(PffOptionsReadNumber(obj->comm, obj->options, obj->prefix, key, PETSC_FALSE, name, sizeof(name), buf,
                                 sizeof(buf), &has, &v, NULL));
  PetscCall(PetscOptionsReal_Private(obj, key, text, man, cur, val, set));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffOptionsInt_Private(PetscOptionItems *obj, const char key[], const char text[], const char man[],
                                     PetscInt cur, PetscInt *val, PetscBool *set, PetscInt lo)
{
  char      name[256], buf[256];
  PetscBool has;
  PetscInt  v = 0;

  PetscFunctionBeginUser;
  PetscCall(PffOptionsReadNumber(obj->comm, obj->options, obj->prefix, key, PETSC_TRUE, name, sizeof(name), buf,
                                 sizeof(buf), &has, NULL, &v));
  PetscCheck(!has || v >= lo, obj->comm, PETSC_ERR_ARG_OUTOFRANGE, "%s %s is invalid: must be >= %" PetscInt_FMT, name,
             buf, lo);
  PetscCall(PetscOptionsInt_Private(obj, key, text, man, cur, val, set, PETSC_MIN_INT, PETSC_MAX_INT));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffOptionsBool_Private(PetscOptionItems *obj, const char key[], const char text[], const char man[],
                                      PetscBool cur, PetscBool *val, PetscBool *set)
{
  static const char *const words[] = {"", "true", "false", "yes", "no", "on", "off", "1", "0"};
  char                     name[256], buf[256];
  PetscBool                has, ok = PETSC_FALSE;

  PetscFunctionBeginUser;
  PetscCall(PffOptionsRaw(obj->options, obj->prefix, key, name, sizeof(name), buf, sizeof(buf), &has));
  if (has)
    for (size_t i = 0; i < PETSC_STATIC_ARRAY_LENGTH(words) && !ok; i++) PetscCall(PetscStrcasecmp(buf, words[i], &ok));
  PetscCheck(!has || ok, obj->comm, PETSC_ERR_ARG_WRONG, "%s %s is invalid: must be true or false", name, buf);
  PetscCall(PetscOptionsBool_Private(obj, key, text, man, cur, val, set));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffOptionsEnum_Private(PetscOptionItems *obj, const char key[], const char text[], const char man[],
                                      const char *const *list, PetscEnum cur, PetscEnum *val, PetscBool *set)
{
  char      name[256], buf[256], choices[512] = "";
  PetscBool has, ok = PETSC_FALSE;
  PetscInt  n = 0;

  PetscFunctionBeginUser;
  while (list[n]) n++;
  PetscCheck(n > 2, PETSC_COMM_SELF, PETSC_ERR_PLIB, "enum list of %s is malformed", key);
  n -= 2; /* the names, then the type name and the prefix (and NULL) */
  PetscCall(PffOptionsRaw(obj->options, obj->prefix, key, name, sizeof(name), buf, sizeof(buf), &has));
  for (PetscInt i = 0; i < n && has && !ok; i++) PetscCall(PetscStrcasecmp(buf, list[i], &ok));
  if (has && !ok) {
    for (PetscInt i = 0; i < n; i++) {
      PetscCall(PetscStrlcat(choices, i ? ", " : "", sizeof(choices)));
      PetscCall(PetscStrlcat(choices, list[i], sizeof(choices)));
    }
    SETERRQ(obj->comm, PETSC_ERR_ARG_UNKNOWN_TYPE, "%s %s is invalid: must be one of %s", name,
            buf[0] ? buf : "(no value)", choices);
  }
  PetscCall(PetscOptionsEnum_Private(obj, key, text, man, list, cur, val, set));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Checks a comma-separated list: at most *n entries, each parsed by the caller's kind. */
static PetscErrorCode PffOptionsCheckList(PetscOptionItems *obj, const char key[], PetscInt nmax, PetscBool integer)
{
  char        name[256], buf[1024];
  PetscBool   has;
  PetscInt    count = 0;
  const char *why   = NULL;

  PetscFunctionBeginUser;
  PetscCall(PffOptionsRaw(obj->options, obj->prefix, key, name, sizeof(name), buf, sizeof(buf), &has));
  if (!has) PetscFunctionReturn(PETSC_SUCCESS);
  for (const char *s = buf; !why;) {
    const char *comma = strchr(s, ',');
    const char *end   = comma ? comma : s + strlen(s);
    PetscReal   r;
    PetscInt    i;

    count++;
    why = PffParseNumber(s, end, integer, &r, &i);
    if (!comma) break;
    s = comma + 1;
  }
  PetscCheck(!why, obj->comm, PETSC_ERR_ARG_WRONG, "%s %s is invalid: %s", name, buf[0] ? buf : "(no value)", why);
  PetscCheck(count <= nmax, obj->comm, PETSC_ERR_ARG_SIZ, "%s %s is invalid: takes %s%" PetscInt_FMT " values", name,
             buf, nmax == 3 ? "" : "at most ", nmax);
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffOptionsRealArray_Private(PetscOptionItems *obj, const char key[], const char text[], const char man[],
                                           PetscReal val[], PetscInt *n, PetscBool *set)
{
  PetscFunctionBeginUser;
  PetscCall(PffOptionsCheckList(obj, key, *n, PETSC_FALSE));
  PetscCall(PetscOptionsRealArray_Private(obj, key, text, man, val, n, set));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffOptionsIntArray_Private(PetscOptionItems *obj, const char key[], const char text[], const char man[],
                                          PetscInt val[], PetscInt *n, PetscBool *set)
{
  PetscFunctionBeginUser;
  PetscCall(PffOptionsCheckList(obj, key, *n, PETSC_TRUE));
  PetscCall(PetscOptionsIntArray_Private(obj, key, text, man, val, n, set));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffOptionsCheckReal(MPI_Comm comm, const char key[], PetscReal lo, PetscReal hi, PetscBool open,
                                   const char range[])
{
  char      name[256], buf[256];
  PetscBool has;
  PetscReal v = 0;

  PetscFunctionBeginUser;
  PetscCall(
      PffOptionsReadNumber(comm, NULL, NULL, key, PETSC_FALSE, name, sizeof(name), buf, sizeof(buf), &has, &v, NULL));
  PetscCheck(!has || (open ? v > lo && v < hi : v >= lo && v <= hi), comm, PETSC_ERR_ARG_OUTOFRANGE,
             "%s %s is invalid: must be %s", key, buf, range);
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffOptionsCheckInt(MPI_Comm comm, const char key[], PetscInt lo, PetscInt hi)
{
  char      name[256], buf[256];
  PetscBool has;
  PetscInt  v = 0;

  PetscFunctionBeginUser;
  PetscCall(
      PffOptionsReadNumber(comm, NULL, NULL, key, PETSC_TRUE, name, sizeof(name), buf, sizeof(buf), &has, NULL, &v));
  PetscCheck(!has || (v >= lo && v <= hi), comm, PETSC_ERR_ARG_OUTOFRANGE,
             "%s %s is invalid: must be in [%" PetscInt_FMT ", %" PetscInt_FMT "]", key, buf, lo, hi);
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffOptionsCheckUnused(MPI_Comm comm)
{
  PetscInt  n     = 0;
  char    **names = NULL, **values = NULL;
  PetscBool help = PETSC_FALSE;

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsHasName(NULL, NULL, "-help", &help));
  if (help) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscOptionsLeftGet(NULL, &n, &names, &values));
  if (n > 0) {
    char key[256];
    PetscCall(PetscSNPrintf(key, sizeof(key), "-%s", names[0]));
    PetscCall(PetscOptionsLeftRestore(NULL, &n, &names, &values));
    SETERRQ(comm, PETSC_ERR_ARG_WRONG,
            "unknown option %s (misspelt, or not used by this scene; -help lists every option)", key);
  }
  PetscCall(PetscOptionsLeftRestore(NULL, &n, &names, &values));
  PetscFunctionReturn(PETSC_SUCCESS);
}
