/* Unit test of the liquid-velocity extrapolation into the air (PF-FLIP Sec. 3.7,
   PffExtrapolateLiquidVelocity) at any rank count.

   (a) Slab: phi_f = 1 below the plane y = 0.3 (32^3 cells, periodic in x and z, walls in y), liquid
       velocity UL, air velocity UA. For N = 0, 1 and 3 layers every open face within N face steps above
       the slab (in its component's lattice) carries exactly UL, every face beyond exactly UA, the closed
       wall faces 0, and the reported number of extrapolated faces is the number of faces 1..N steps up.
   (b) Layer rule: two liquid spheres (one across the periodic x boundary) with a linear liquid velocity;
       the result equals, bit for bit, a serial reference of the rule (6-neighbour mean, previous layer's
       mask only) evaluated on every rank from the gathered inputs. So it is the same on 1, 2 and 4 ranks.
   (c) Two levels: fine blocks below y = 0.5 where x < 0.5 and above it where x >= 0.5, coarse elsewhere;
       slab below y = 0.47. With a constant liquid velocity every value is finite and either UL (to 1e-6)
       or UA, and faces of the coarse blocks at x < 0.25 above the fine slab and of the fine blocks at
       x >= 0.75 above the coarse slab got UL: both only reachable across a level boundary. With a
       liquid velocity linear in x every value is finite and inside the range of the liquid faces'
       values, widened by half a coarse cell of slope (where the grid extrapolates ghosts linearly). With one
       layer the lowest coarse x-faces above the fine slab, whose ghost below has mask exactly 1/2, take UL.
   (d) Two fields at once (PffExtrapolateLiquidVelocities) equal two separate calls bit for bit, also with the
       layers on a width-1 work channel for the wide field (as the flow runs them).

   Sample run:  mpiexec -n 4 ./test_flow_extrapolate
   Prints the same lines on any number of ranks. */
#include "pfftest.h"
#include <string.h>

static const char help[] = "Liquid-velocity extrapolation into the air (Sec. 3.7).\n";

#define N0 8
#define NB 4 /* blocks per axis */

static const PetscReal UL[3] = {1.0, -2.0, 0.5}, UA[3] = {-3.0, 4.0, 7.0};

typedef enum { REGION_SLAB, REGION_SPHERES } Region;
typedef enum { VEL_CONSTANT, VEL_LINEAR, VEL_LINEAR_X } Velocity;

typedef struct {
  const PffTestCtx *t;
  Region            region;
  Velocity          vel;
  PetscReal         y0; /* slab top */
} Scene;

typedef struct {
  PetscInt u, phi, open, mask, ul;
} Channels;

static PetscBool InSphere(const Scene *s, const PetscReal x[3], const PetscReal c[3], PetscReal r)
{
  PetscReal d2 = 0;
  for (int a = 0; a < 3; a++) {
    PetscReal d = x[a] - c[a];
    if (s->t->periodic[a]) {
      const PetscReal L = s->t->blen * (PetscReal)s->t->nb[a];
      d -= L * PetscFloorReal(d / L + 0.5);
    }
    d2 += d * d;
  }
  return d2 < r * r ? PETSC_TRUE : PETSC_FALSE;
}

static PetscBool Liquid(const Scene *s, const PetscReal x[3])
{
  const PetscReal ca[3] = {0.45, 0.42, 0.55}, cb[3] = {0.02, 0.7, 0.3};
  if (s->region == REGION_SLAB) return x[1] < s->y0 ? PETSC_TRUE : PETSC_FALSE;
  return InSphere(s, x, ca, 0.2) || InSphere(s, x, cb, 0.15) ? PETSC_TRUE : PETSC_FALSE;
}

/* the lower domain wall of a walled axis is a closed face (the upper one is a zero ghost) */
static PetscBool Closed(const Scene *s, const PetscReal x[3], PetscInt comp)
{
  return !s->t->periodic[comp] && PetscAbsReal(x[comp] - s->t->origin[comp]) < 1e-3 * s->t->h0 ? PETSC_TRUE
                                                                                               : PETSC_FALSE;
}

static PetscReal LiquidVelocity(const Scene *s, PetscInt comp, const PetscReal x[3])
{
  switch (s->vel) {
  case VEL_LINEAR:
    return PffTestLinear(s->t, comp, x);
  case VEL_LINEAR_X:
    return UL[comp] + 0.8 * x[0];
  default:
    return UL[comp];
  }
}

static PetscReal FillPhi(const PetscReal x[3], PetscInt comp, void *ctx)
{
  (void)comp;
  return Liquid((const Scene *)ctx, x) ? 1.0 : 0.0;
}

static PetscReal FillOpen(const PetscReal x[3], PetscInt comp, void *ctx)
{
  return Closed((const Scene *)ctx, x, comp) ? 0.0 : 1.0;
}

/* the mixture velocity of a projection: liquid velocity on liquid faces, air velocity elsewhere */
static PetscReal FillU(const PetscReal x[3], PetscInt comp, void *ctx)
{
  const Scene *s = (const Scene *)ctx;
  if (Closed(s, x, comp)) return 0.0;
  return Liquid(s, x) ? LiquidVelocity(s, comp, x) : UA[comp];
}

static PetscErrorCode Extrapolate(const PffTestCtx *t, Scene *s, const Channels *ch, PetscInt layers, PetscInt64 *faces)
{
  PetscFunctionBeginUser;
  PetscCall(PffGridFillChannel(t->grid, ch->phi, FillPhi, s));
  PetscCall(PffGridFillChannel(t->grid, ch->open, FillOpen, s));
  PetscCall(PffGridFillChannel(t->grid, ch->u, FillU, s));
  /* the flow exchanges these before; so do we (the kernel reads no ghost of u, phi or open) */
  PetscCall(PffGridHaloBegin(t->grid, ch->u));
  PetscCall(PffGridHaloEnd(t->grid, ch->u));
  PetscCall(PffExtrapolateLiquidVelocity(t->grid, ch->u, ch->phi, ch->open, layers, ch->mask, ch->ul, -1, faces));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode AddChannels(PffGrid grid, Channels *ch)
{
  PetscFunctionBeginUser;
  PetscCall(PffGridAddChannel(grid, "u", PFF_CHANNEL_FACE, 2, &ch->u));
  PetscCall(PffGridAddChannel(grid, "phi_face", PFF_CHANNEL_FACE, 1, &ch->phi));
  PetscCall(PffGridAddChannel(grid, "open", PFF_CHANNEL_FACE, 1, &ch->open));
  PetscCall(PffGridAddChannel(grid, "mask", PFF_CHANNEL_FACE, 1, &ch->mask));
  PetscCall(PffGridAddChannel(grid, "u_liquid", PFF_CHANNEL_FACE, 2, &ch->ul));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Face steps of the comp-face at height y above the topmost liquid face of its column (slab top y0). */
static PetscInt SlabLayer(const PffTestCtx *t, PetscInt comp, PetscReal y, PetscReal y0)
{
  const PetscReal o = comp == 1 ? 0.0 : 0.5;
  if (y < y0) return 0;
  const PetscInt j = (PetscInt)PetscFloorReal((y - t->origin[1]) / t->h0 - o + 0.5);
  /* largest index with (jt + o) h0 < y0 */
  const PetscInt jt = (PetscInt)PetscCeilReal((y0 - t->origin[1]) / t->h0 - o) - 1;
  return j - jt;
}

static PetscErrorCode TestSlab(MPI_Comm comm)
{
  const PetscInt  nb[3]       = {NB, NB, NB};
  const PetscBool periodic[3] = {PETSC_TRUE, PETSC_FALSE, PETSC_TRUE};
  const PetscReal origin[3]   = {0, 0, 0};
  const PetscInt  layers[3]   = {0, 1, 3};
  PffTestCtx      t;
  Channels        ch;

  PetscFunctionBeginUser;
  PetscCall(PffTestCreateGrid(comm, nb, periodic, origin, 1.0 / (N0 * NB), N0, 1, 0, 0, 7, &t));
  PetscCall(AddChannels(t.grid, &ch));
  Scene s = {&t, REGION_SLAB, VEL_CONSTANT, 0.3};
  for (PetscInt q = 0; q < 3; q++) {
    const PetscInt N   = layers[q];
    PetscInt64     cnt = 0, bad = 0, faces = 0;
    PetscCall(Extrapolate(&t, &s, &ch, N, &faces));
    for (PetscInt lb = 0; lb < t.nlocal; lb++) {
      PffBlockInfo info;
      PetscCall(PffGridGetBlockInfo(t.grid, lb, &info));
      for (PetscInt d = 0; d < 3; d++) {
        float *ul;
        PetscCall(PffGridGetBlockData(t.grid, ch.ul, lb, d, &ul));
        for (PetscInt k = 0; k < info.n; k++)
          for (PetscInt j = 0; j < info.n; j++)
            for (PetscInt i = 0; i < info.n; i++) {
              const PetscInt c[3] = {i, j, k};
              PetscReal      x[3];
              PffTestSamplePosition(&info, PFF_CHANNEL_FACE, d, c, x);
              const PetscInt L      = SlabLayer(&t, d, x[1], s.y0);
              const float    expect = Closed(&s, x, d) ? 0.0f : (L <= N ? (float)UL[d] : (float)UA[d]);
              if (L >= 1 && L <= N && !Closed(&s, x, d)) cnt++;
              if (ul[i + info.n * (j + info.n * k)] != expect) bad++;
            }
      }
    }
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &cnt, 1, MPIU_INT64, MPI_SUM, comm));
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &bad, 1, MPIU_INT64, MPI_SUM, comm));
    PetscCall(PetscPrintf(
        comm, "slab, %" PetscInt_FMT " layers: %" PetscInt64_FMT " faces extrapolated, %" PetscInt64_FMT " wrong\n", N,
        faces, bad));
    PetscCheck(bad == 0, comm, PETSC_ERR_PLIB,
               "slab, %" PetscInt_FMT " layers: %" PetscInt64_FMT " faces differ from the layer rule", N, bad);
    PetscCheck(faces == cnt, comm, PETSC_ERR_PLIB,
               "slab, %" PetscInt_FMT " layers: %" PetscInt64_FMT " faces reported, %" PetscInt64_FMT " expected", N,
               faces, cnt);
  }
  PetscCall(PffGridDestroy(&t.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The layer rule on global arrays of a uniform grid of m faces per axis and component (x fastest),
   written independently of the grid: closed faces and faces across a wall are never valid. */
static void ReferenceRule(const PffTestCtx *t, PetscInt m, PetscInt layers, const float *u, const float *phi,
                          const float *open, float *ul, float *mask, float *next)
{
  const PetscInt m3 = m * m * m;
  for (PetscInt f = 0; f < 3 * m3; f++) {
    mask[f] = open[f] > 0 && phi[f] >= 0.5f ? 1.0f : 0.0f;
    ul[f]   = mask[f] > 0 ? u[f] : 0.0f;
  }
  for (PetscInt l = 0; l < layers; l++) {
    for (PetscInt f = 0; f < 3 * m3; f++) next[f] = mask[f];
    for (PetscInt d = 0; d < 3; d++)
      for (PetscInt k = 0; k < m; k++)
        for (PetscInt j = 0; j < m; j++)
          for (PetscInt i = 0; i < m; i++) {
            const PetscInt f = d * m3 + i + m * (j + m * k);
            if (mask[f] > 0 || !(open[f] > 0)) continue;
            PetscReal sum = 0;
            PetscInt  cnt = 0;
            for (PetscInt q = 0; q < 6; q++) {
              const PetscInt s = q % 2 ? 1 : -1, ax = q / 2;
              PetscInt       g[3] = {i, j, k};
              g[ax] += s;
              if (g[ax] < 0 || g[ax] >= m) {
                if (!t->periodic[ax]) continue;
                g[ax] = (g[ax] + m) % m;
              }
              const PetscInt fn = d * m3 + g[0] + m * (g[1] + m * g[2]);
              if (mask[fn] > 0) {
                sum += (PetscReal)ul[fn];
                cnt++;
              }
            }
            if (cnt) {
              ul[f]   = (float)(sum / (PetscReal)cnt);
              next[f] = 1.0f;
            }
          }
    for (PetscInt f = 0; f < 3 * m3; f++) mask[f] = next[f];
  }
  for (PetscInt f = 0; f < 3 * m3; f++)
    if (!(mask[f] > 0)) ul[f] = open[f] > 0 ? u[f] : 0.0f;
}

/* Owned values of component d of channel ch scattered into (or, with gather false, compared against) the
   global array g of a uniform grid. */
static PetscErrorCode GlobalArray(const PffTestCtx *t, PetscInt ch, PetscInt m, float *g, PetscBool gather,
                                  PetscInt64 *bad)
{
  PetscFunctionBeginUser;
  for (PetscInt lb = 0; lb < t->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(t->grid, lb, &info));
    const PetscInt n = info.n;
    for (PetscInt d = 0; d < 3; d++) {
      float *v;
      PetscCall(PffGridGetBlockData(t->grid, ch, lb, d, &v));
      for (PetscInt k = 0; k < n; k++)
        for (PetscInt j = 0; j < n; j++)
          for (PetscInt i = 0; i < n; i++) {
            const PetscInt f =
                d * m * m * m + (info.ijk[0] * n + i) + m * ((info.ijk[1] * n + j) + m * (info.ijk[2] * n + k));
            if (gather)
              g[f] = v[i + n * (j + n * k)];
            else if (g[f] != v[i + n * (j + n * k)])
              (*bad)++;
          }
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode TestRule(MPI_Comm comm)
{
  const PetscInt  nb[3]       = {NB, NB, NB};
  const PetscBool periodic[3] = {PETSC_TRUE, PETSC_FALSE, PETSC_FALSE};
  const PetscReal origin[3]   = {0, 0, 0};
  const PetscInt  m = N0 * NB, nf = 3 * m * m * m, layers = 3;
  PffTestCtx      t;
  Channels        ch;
  float          *u, *phi, *open, *ul, *mask, *next;
  PetscInt64      bad = 0, faces = 0, changed = 0;

  PetscFunctionBeginUser;
  PetscCall(PffTestCreateGrid(comm, nb, periodic, origin, 1.0 / m, N0, 1, 0, 0, 11, &t));
  PetscCall(AddChannels(t.grid, &ch));
  Scene s = {&t, REGION_SPHERES, VEL_LINEAR, 0};
  PetscCall(Extrapolate(&t, &s, &ch, layers, &faces));
  PetscCall(PetscCalloc3(nf, &u, nf, &phi, nf, &open));
  PetscCall(PetscMalloc3(nf, &ul, nf, &mask, nf, &next));
  PetscCall(GlobalArray(&t, ch.u, m, u, PETSC_TRUE, NULL));
  PetscCall(GlobalArray(&t, ch.phi, m, phi, PETSC_TRUE, NULL));
  PetscCall(GlobalArray(&t, ch.open, m, open, PETSC_TRUE, NULL));
  /* every face is owned once: the sum is the gather */
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, u, (PetscMPIInt)nf, MPI_FLOAT, MPI_SUM, comm));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, phi, (PetscMPIInt)nf, MPI_FLOAT, MPI_SUM, comm));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, open, (PetscMPIInt)nf, MPI_FLOAT, MPI_SUM, comm));
  ReferenceRule(&t, m, layers, u, phi, open, ul, mask, next);
  PetscCall(GlobalArray(&t, ch.ul, m, ul, PETSC_FALSE, &bad));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &bad, 1, MPIU_INT64, MPI_SUM, comm));
  /* a rank-independent checksum of the reference, and how many faces the extrapolation changed */
  PetscReal sum = 0;
  for (PetscInt f = 0; f < nf; f++) {
    sum += (PetscReal)ul[f] * (PetscReal)(1 + f % 97);
    if (ul[f] != u[f]) changed++;
  }
  PetscCall(PetscPrintf(comm,
                        "rule, %" PetscInt_FMT " layers: %" PetscInt64_FMT " faces extrapolated (%" PetscInt64_FMT
                        " changed), checksum %.10e, %" PetscInt64_FMT " differ from the reference\n",
                        layers, faces, changed, (double)sum, bad));
  PetscCheck(bad == 0, comm, PETSC_ERR_PLIB, "%" PetscInt64_FMT " faces differ from the serial layer rule", bad);
  /* the linear field makes extrapolated values differ from the air velocity on every component */
  PetscCheck(changed == faces && faces > 0, comm, PETSC_ERR_PLIB,
             "%" PetscInt64_FMT " faces extrapolated but %" PetscInt64_FMT " changed", faces, changed);
  PetscCall(PetscFree3(u, phi, open));
  PetscCall(PetscFree3(ul, mask, next));
  PetscCall(PffGridDestroy(&t.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Fine (level 0) blocks below y = 0.5 at x < 0.5 and above it at x >= 0.5, coarse (level 1) elsewhere. */
static PetscErrorCode CreateTwoLevelGrid(MPI_Comm comm, PffTestCtx *t)
{
  const PetscInt  nb[3]       = {NB, NB, NB};
  const PetscBool periodic[3] = {PETSC_FALSE, PETSC_FALSE, PETSC_TRUE};
  const PetscReal origin[3]   = {0, 0, 0};
  PetscInt        level[NB * NB * NB];

  PetscFunctionBeginUser;
  for (PetscInt k = 0; k < NB; k++)
    for (PetscInt j = 0; j < NB; j++)
      for (PetscInt i = 0; i < NB; i++)
        level[i + NB * (j + NB * k)] = ((i < NB / 2 && j == 1) || (i >= NB / 2 && j == 2)) ? 0 : 1;
  PetscCall(PffTestCreateGridFromMap(comm, nb, periodic, origin, 1.0 / (N0 * NB), N0, 2, level, t));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The mask rule at a level boundary: the lowest x-faces of a coarse block above the fine slab (y = 0.5 +
   h_c/2) have, below them, a ghost that averages one liquid and one air fine x-face (mask exactly 1/2). With
   one layer they must take UL (valid at >= 1/2), the x-faces one coarse cell higher must keep UA. */
static PetscErrorCode TestHalfMask(const PffTestCtx *t, const Channels *ch)
{
  Scene      s      = {t, REGION_SLAB, VEL_CONSTANT, 0.47};
  PetscInt64 cnt[3] = {0, 0, 0}; /* lowest row, liquid there, second row still air */

  PetscFunctionBeginUser;
  PetscCall(Extrapolate(t, &s, ch, 1, NULL));
  for (PetscInt lb = 0; lb < t->nlocal; lb++) {
    PffBlockInfo info;
    float       *ul, *open;
    PetscCall(PffGridGetBlockInfo(t->grid, lb, &info));
    if (!(info.ijk[0] == 0 && info.ijk[1] == 2)) continue;
    PetscCall(PffGridGetBlockData(t->grid, ch->ul, lb, 0, &ul));
    PetscCall(PffGridGetBlockData(t->grid, ch->open, lb, 0, &open));
    const PetscInt n = info.n;
    for (PetscInt k = 0; k < n; k++)
      for (PetscInt i = 0; i < n; i++) {
        if (!(open[i + n * n * k] > 0)) continue; /* the x wall */
        cnt[0]++;
        if (ul[i + n * (0 + n * k)] == (float)UL[0]) cnt[1]++;
        if (ul[i + n * (1 + n * k)] == (float)UA[0]) cnt[2]++;
      }
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, cnt, 3, MPIU_INT64, MPI_SUM, t->comm));
  PetscCall(PetscPrintf(t->comm,
                        "two levels, one layer: %" PetscInt64_FMT " of %" PetscInt64_FMT
                        " coarse x-faces above a half-valid fine ghost took UL, %" PetscInt64_FMT " above kept UA\n",
                        cnt[1], cnt[0], cnt[2]));
  PetscCheck(cnt[0] > 0 && cnt[1] == cnt[0] && cnt[2] == cnt[0], t->comm, PETSC_ERR_PLIB,
             "a ghost with interpolated mask 1/2 must count as valid (and only for one layer)");
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode TestLevels(MPI_Comm comm)
{
  const PetscInt layers = 3;
  PffTestCtx     t;
  Channels       ch;

  PetscFunctionBeginUser;
  PetscCall(CreateTwoLevelGrid(comm, &t));
  PetscCall(AddChannels(t.grid, &ch));
  const Velocity vels[2] = {VEL_CONSTANT, VEL_LINEAR_X};
  for (PetscInt q = 0; q < 2; q++) {
    const Velocity vel    = vels[q];
    Scene          s      = {&t, REGION_SLAB, vel, 0.47};
    PetscInt64     cnt[4] = {0, 0, 0, 0}; /* not finite, out of range, across fine -> coarse, across coarse -> fine */
    PetscReal      lo[3], hi[3];
    PetscCall(Extrapolate(&t, &s, &ch, layers, NULL));
    for (PetscInt d = 0; d < 3; d++) {
      PetscReal range[2] = {-PETSC_MAX_REAL, -PETSC_MAX_REAL}; /* -min, max over the liquid faces */
      for (PetscInt lb = 0; lb < t.nlocal; lb++) {
        PffBlockInfo info;
        float       *u, *phi, *open;
        PetscCall(PffGridGetBlockInfo(t.grid, lb, &info));
        PetscCall(PffGridGetBlockData(t.grid, ch.u, lb, d, &u));
        PetscCall(PffGridGetBlockData(t.grid, ch.phi, lb, d, &phi));
        PetscCall(PffGridGetBlockData(t.grid, ch.open, lb, d, &open));
        /* the sources: open liquid faces (closed wall faces hold 0 and would widen the range) */
        for (PetscInt c = 0; c < info.n * info.n * info.n; c++)
          if (phi[c] >= 0.5f && open[c] > 0) {
            range[0] = PetscMax(range[0], -(PetscReal)u[c]);
            range[1] = PetscMax(range[1], (PetscReal)u[c]);
          }
      }
      PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, range, 2, MPIU_REAL, MPI_MAX, comm));
      /* the grid extrapolates coarse ghosts linearly up to half a coarse cell beyond its source box */
      const PetscReal widen = vel == VEL_LINEAR_X ? 0.8 * 0.5 * 2 * t.h0 : 0.0;
      lo[d]                 = -range[0] - widen - 1e-5;
      hi[d]                 = range[1] + widen + 1e-5;
    }
    for (PetscInt lb = 0; lb < t.nlocal; lb++) {
      PffBlockInfo info;
      PetscCall(PffGridGetBlockInfo(t.grid, lb, &info));
      const PetscBool f2c = (PetscBool)(info.ijk[0] == 0 && info.ijk[1] == 2);
      const PetscBool c2f = (PetscBool)(info.ijk[0] == NB - 1 && info.ijk[1] == 2);
      for (PetscInt d = 0; d < 3; d++) {
        float *ul, *open;
        PetscCall(PffGridGetBlockData(t.grid, ch.ul, lb, d, &ul));
        PetscCall(PffGridGetBlockData(t.grid, ch.open, lb, d, &open));
        for (PetscInt c = 0; c < info.n * info.n * info.n; c++) {
          const PetscReal v = (PetscReal)ul[c];
          if (PetscIsInfOrNanReal(v)) {
            cnt[0]++;
            continue;
          }
          if (!(open[c] > 0)) continue;
          const PetscBool air = (PetscBool)(v == (PetscReal)(float)UA[d]);
          if (vel == VEL_CONSTANT && !air && PetscAbsReal(v - UL[d]) > 1e-6 * PetscAbsReal(UL[d])) cnt[1]++;
          if (vel == VEL_LINEAR_X && !air && (v < lo[d] || v > hi[d])) cnt[1]++;
          if (!air && f2c) cnt[2]++;
          if (!air && c2f) cnt[3]++;
        }
      }
    }
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, cnt, 4, MPIU_INT64, MPI_SUM, comm));
    PetscCall(PetscPrintf(comm,
                          "two levels, %s liquid velocity: %" PetscInt64_FMT " not finite, %" PetscInt64_FMT
                          " out of range, %" PetscInt64_FMT " faces reached across fine -> coarse, %" PetscInt64_FMT
                          " across coarse -> fine\n",
                          vel == VEL_CONSTANT ? "constant" : "linear", cnt[0], cnt[1], cnt[2], cnt[3]));
    PetscCheck(cnt[0] == 0, comm, PETSC_ERR_PLIB, "%" PetscInt64_FMT " extrapolated values are not finite", cnt[0]);
    PetscCheck(cnt[1] == 0, comm, PETSC_ERR_PLIB, "%" PetscInt64_FMT " extrapolated values leave the source range",
               cnt[1]);
    PetscCheck(cnt[2] > 0 && cnt[3] > 0, comm, PETSC_ERR_PLIB,
               "the extrapolation did not cross the level boundary (%" PetscInt64_FMT
               " fine -> coarse, %" PetscInt64_FMT " coarse -> fine faces)",
               cnt[2], cnt[3]);
  }
  PetscCall(TestHalfMask(&t, &ch));
  PetscCall(PffGridDestroy(&t.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Owned faces of face channel src into dst, or (cmp) the number of owned faces where they differ in any bit. */
static PetscErrorCode CopyOrCompare(const PffTestCtx *t, PetscInt src, PetscInt dst, PetscBool cmp, PetscInt64 *ndiff)
{
  PetscFunctionBeginUser;
  for (PetscInt lb = 0; lb < t->nlocal; lb++)
    for (PetscInt d = 0; d < 3; d++) {
      PffBlockInfo info;
      float       *a, *b;
      PetscCall(PffGridGetBlockInfo(t->grid, lb, &info));
      PetscCall(PffGridGetBlockData(t->grid, src, lb, d, &a));
      PetscCall(PffGridGetBlockData(t->grid, dst, lb, d, &b));
      const PetscInt n3 = info.n * info.n * info.n;
      if (!cmp)
        PetscCall(PetscArraycpy(b, a, n3));
      else
        for (PetscInt c = 0; c < n3; c++) *ndiff += memcmp(&a[c], &b[c], sizeof(float)) != 0;
    }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* (d) Two fields at once (PffExtrapolateLiquidVelocities, as the liquid model extrapolates u and its change): on
   the two-level grid, a liquid velocity linear in x and one linear in every coordinate give, bit for bit, what two
   separate calls give, and the same count of extrapolated faces; with the layers of the first (width-2) field on a
   width-1 work channel too, as the flow runs them (a layer reads one ghost face, and the first ghost layer of a
   width-1 exchange is that of a width-2 one). */
static PetscErrorCode TestTwoFields(MPI_Comm comm)
{
  const PetscInt layers = 3;
  PffTestCtx     t;
  Channels       ch;
  PetscInt       u2, ul2, ref[2], work;
  PetscInt64     total = 0, faces[2];

  PetscFunctionBeginUser;
  PetscCall(CreateTwoLevelGrid(comm, &t));
  PetscCall(AddChannels(t.grid, &ch));
  PetscCall(PffGridAddChannel(t.grid, "u2", PFF_CHANNEL_FACE, 2, &u2));
  PetscCall(PffGridAddChannel(t.grid, "u2_liquid", PFF_CHANNEL_FACE, 2, &ul2));
  PetscCall(PffGridAddChannel(t.grid, "ref1", PFF_CHANNEL_FACE, 1, &ref[0]));
  PetscCall(PffGridAddChannel(t.grid, "ref2", PFF_CHANNEL_FACE, 1, &ref[1]));
  PetscCall(PffGridAddChannel(t.grid, "work", PFF_CHANNEL_FACE, 1, &work));
  Scene s1 = {&t, REGION_SLAB, VEL_LINEAR_X, 0.47}, s2 = {&t, REGION_SLAB, VEL_LINEAR, 0.47};
  /* the separate calls (the same liquid faces: only the velocity differs) */
  PetscCall(Extrapolate(&t, &s2, &ch, layers, &faces[1]));
  PetscCall(CopyOrCompare(&t, ch.ul, ref[1], PETSC_FALSE, NULL));
  PetscCall(Extrapolate(&t, &s1, &ch, layers, &faces[0]));
  PetscCall(CopyOrCompare(&t, ch.ul, ref[0], PETSC_FALSE, NULL));
  for (PetscInt lb = 0; lb < t.nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(t.grid, lb, &info));
    total += 6 * info.n * info.n * info.n;
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &total, 1, MPIU_INT64, MPI_SUM, comm));
  for (PetscInt useWork = 0; useWork < 2; useWork++) {
    const PetscInt src[2] = {ch.u, u2}, dst[2] = {ch.ul, ul2}, wk[2] = {work, -1};
    PetscInt64     bad = 0, fused;
    /* the fused call: ch.u holds field 1, u2 field 2 */
    PetscCall(PffGridFillChannel(t.grid, u2, FillU, &s2));
    PetscCall(PffGridHaloBegin(t.grid, u2));
    PetscCall(PffGridHaloEnd(t.grid, u2));
    PetscCall(PffGridFillChannel(t.grid, ch.ul, FillU, &s2)); /* stale values that the call must overwrite */
    PetscCall(PffGridFillChannel(t.grid, work, FillU, &s1));
    PetscCall(PffExtrapolateLiquidVelocities(t.grid, 2, src, ch.phi, ch.open, layers, ch.mask, dst, useWork ? wk : NULL,
                                             &fused));
    PetscCall(CopyOrCompare(&t, ch.ul, ref[0], PETSC_TRUE, &bad));
    PetscCall(CopyOrCompare(&t, ul2, ref[1], PETSC_TRUE, &bad));
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &bad, 1, MPIU_INT64, MPI_SUM, comm));
    PetscCall(PetscPrintf(comm,
                          "two fields at once%s: %" PetscInt64_FMT " of %" PetscInt64_FMT
                          " faces differ from two separate calls; %" PetscInt64_FMT
                          " faces extrapolated (%" PetscInt64_FMT " and %" PetscInt64_FMT " separately)\n",
                          useWork ? ", layers on a width-1 work channel" : "", bad, total, fused, faces[0], faces[1]));
    PetscCheck(bad == 0, comm, PETSC_ERR_PLIB, "%" PetscInt64_FMT " faces differ from two separate calls", bad);
    PetscCheck(fused == faces[0] && fused == faces[1], comm, PETSC_ERR_PLIB, "extrapolated face counts differ");
  }
  PetscCall(PffGridDestroy(&t.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(PffInitializePackage());
  PetscCall(TestSlab(PETSC_COMM_WORLD));
  PetscCall(TestRule(PETSC_COMM_WORLD));
  PetscCall(TestLevels(PETSC_COMM_WORLD));
  PetscCall(TestTwoFields(PETSC_COMM_WORLD));
  PetscCall(PetscFinalize());
  return 0;
}
