/* Unit test of the Morton (Z-order) keys of core.h: PffMortonEncode and PffMortonDecode.

   Checks that decode(encode(x, y, z)) == (x, y, z) for the corners 0 and 2^21 - 1 of each axis and
   for 200000 pseudo-random triples; that encode(decode(k)) == k for every key below 2^15 and for
   pseudo-random 63-bit keys; that the 2x2x2 cube is numbered 0..7 with x in the lowest bit; that the
   keys of a 16^3 cube are exactly 0..4095 (a bijection); and that the curve is hierarchical:
   encode(x, y, z) >> 3 == encode(x >> 1, y >> 1, z >> 1).

   Sample run:  ./test_morton
   Prints:      morton ok: <n> round trips, <m> keys */
#include "pfftest.h"

static const char help[] = "Morton key round trips and Z-order.\n";

#define MORTON_MAX ((uint32_t)((1u << 21) - 1))

/* splitmix64: a counter-based generator, so the sequence does not depend on anything but i. */
static PetscErrorCode CheckRoundTrip(uint32_t x, uint32_t y, uint32_t z)
{
  uint32_t       a, b, c;
  const uint64_t key = PffMortonEncode(x, y, z);

  PetscFunctionBeginUser;
  PffMortonDecode(key, &a, &b, &c);
  PetscCheck(a == x && b == y && c == z, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "decode(encode(%u, %u, %u)) = (%u, %u, %u), key %llu", x, y, z, a, b, c, (unsigned long long)key);
  PetscCheck(key < (1ULL << 63), PETSC_COMM_SELF, PETSC_ERR_PLIB, "encode(%u, %u, %u) = %llu uses more than 63 bits", x,
             y, z, (unsigned long long)key);
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  PetscInt ntrips = 0, nkeys = 0;

  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(PffInitializePackage());

  /* corners of the key space, and single bits on each axis */
  const uint32_t special[] = {0, 1, 2, 3, 1u << 10, (1u << 20) - 1, 1u << 20, MORTON_MAX - 1, MORTON_MAX};
  const int      nspecial  = (int)PETSC_STATIC_ARRAY_LENGTH(special);
  for (int i = 0; i < nspecial; i++)
    for (int j = 0; j < nspecial; j++)
      for (int k = 0; k < nspecial; k++, ntrips++) PetscCall(CheckRoundTrip(special[i], special[j], special[k]));
  PetscCheck(PffMortonEncode(MORTON_MAX, MORTON_MAX, MORTON_MAX) == (1ULL << 63) - 1, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "encode of the largest coordinates is %llu, expected 2^63 - 1",
             (unsigned long long)PffMortonEncode(MORTON_MAX, MORTON_MAX, MORTON_MAX));
  for (int b = 0; b < 21; b++) {
    const uint32_t v = 1u << b;
    PetscCheck(PffMortonEncode(v, 0, 0) == 1ULL << (3 * b) && PffMortonEncode(0, v, 0) == 1ULL << (3 * b + 1) &&
                   PffMortonEncode(0, 0, v) == 1ULL << (3 * b + 2),
               PETSC_COMM_SELF, PETSC_ERR_PLIB, "bit %d of an axis does not go to key bit 3*%d + axis", b, b);
  }

  /* pseudo-random triples over the full 21-bit range */
  for (uint64_t n = 0; n < 200000; n++, ntrips++) {
    const uint64_t r = PffTestHash64(n);
    PetscCall(CheckRoundTrip((uint32_t)(r & MORTON_MAX), (uint32_t)((r >> 21) & MORTON_MAX),
                             (uint32_t)((r >> 42) & MORTON_MAX)));
  }

  /* keys -> coordinates -> keys, densely for small keys and randomly for large ones */
  for (uint64_t key = 0; key < (1u << 15); key++, nkeys++) {
    uint32_t x, y, z;
    PffMortonDecode(key, &x, &y, &z);
    PetscCheck(PffMortonEncode(x, y, z) == key, PETSC_COMM_SELF, PETSC_ERR_PLIB, "encode(decode(%llu)) = %llu",
               (unsigned long long)key, (unsigned long long)PffMortonEncode(x, y, z));
  }
  for (uint64_t n = 0; n < 100000; n++, nkeys++) {
    const uint64_t key = PffTestHash64(n + 0x5eed) >> 1;
    uint32_t       x, y, z;
    PffMortonDecode(key, &x, &y, &z);
    PetscCheck(x <= MORTON_MAX && y <= MORTON_MAX && z <= MORTON_MAX && PffMortonEncode(x, y, z) == key,
               PETSC_COMM_SELF, PETSC_ERR_PLIB, "encode(decode(%llu)) = %llu", (unsigned long long)key,
               (unsigned long long)PffMortonEncode(x, y, z));
  }

  /* Z-order of the unit cube: x is the lowest bit, then y, then z */
  for (uint32_t z = 0; z < 2; z++)
    for (uint32_t y = 0; y < 2; y++)
      for (uint32_t x = 0; x < 2; x++)
        PetscCheck(PffMortonEncode(x, y, z) == x + 2 * y + 4 * z, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                   "encode(%u, %u, %u) = %llu, expected %u", x, y, z, (unsigned long long)PffMortonEncode(x, y, z),
                   x + 2 * y + 4 * z);

  /* a 16^3 cube maps onto 0..4095 one to one, and the curve is self-similar under halving */
  {
    PetscBool seen[4096] = {PETSC_FALSE};
    for (uint32_t z = 0; z < 16; z++)
      for (uint32_t y = 0; y < 16; y++)
        for (uint32_t x = 0; x < 16; x++) {
          const uint64_t key = PffMortonEncode(x, y, z);
          PetscCheck(key < 4096 && !seen[key], PETSC_COMM_SELF, PETSC_ERR_PLIB,
                     "encode(%u, %u, %u) = %llu is out of [0, 4096) or repeated", x, y, z, (unsigned long long)key);
          seen[key] = PETSC_TRUE;
          PetscCheck(key >> 3 == PffMortonEncode(x >> 1, y >> 1, z >> 1) &&
                         (key & 7) == PffMortonEncode(x & 1, y & 1, z & 1),
                     PETSC_COMM_SELF, PETSC_ERR_PLIB, "encode(%u, %u, %u) is not the parent key followed by the octant",
                     x, y, z);
        }
  }
  for (uint64_t n = 0; n < 10000; n++) {
    const uint64_t r = PffTestHash64(n + 0xc0ffee);
    const uint32_t x = (uint32_t)(r & MORTON_MAX), y = (uint32_t)((r >> 21) & MORTON_MAX),
                   z = (uint32_t)((r >> 42) & MORTON_MAX);
    PetscCheck(PffMortonEncode(x, y, z) >> 3 == PffMortonEncode(x >> 1, y >> 1, z >> 1), PETSC_COMM_SELF,
               PETSC_ERR_PLIB, "encode(%u, %u, %u) >> 3 differs from the parent key", x, y, z);
  }

  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "morton ok: %" PetscInt_FMT " round trips, %" PetscInt_FMT " keys\n", ntrips,
                        nkeys));
  PetscCall(PetscFinalize());
  return 0;
}
