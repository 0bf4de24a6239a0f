/*
 * The page learner's batch of the 2-D LQG (Section 5.2) as a WebAssembly kernel: the same
 * arithmetic as LqgBatch.prototype.run2gb in ../static/lqg_task.js (G(PO)MDP with the
 * variance-minimising baselines, clipped states and actions, the clipped-action score) and
 * the same normals as Rng.prototype.fillNormal in ../static/learner.js, so that a seeded run
 * gives the same bits with or without it (tests/test_wasm_kernel.py checks that).
 *
 * Why it is bit-identical to the JavaScript:
 *   - every sum and product is written in the JavaScript's order, and WebAssembly's f64
 *     arithmetic is IEEE-754 round-to-nearest with no fused multiply-add (the SIMD proposal
 *     has none; -ffp-contract=off says so to the compiler as well);
 *   - two trajectories share one f64x2 vector, each lane doing one trajectory's scalar
 *     operations; the batch sums (the baselines' numerators and denominators) add lane 0
 *     then lane 1, trajectory after trajectory, as the JavaScript loop does;
 *   - the clip min(max(a, -b), b) is pmin(pmax(a, -b), b) (both are a < -b ? -b : a, then
 *     b < x ? b : x, NaN kept as the JavaScript keeps it);
 *   - the ziggurat's tables come from the JavaScript (copied in, not recomputed), and its
 *     slow path calls the page's own Math.log (imported), and Math.exp whenever a bracket
 *     of it (below_exp) cannot settle the wedge test, which is about never.
 *
 * Build: `make wasm` (clang through the pinned ziglang package) writes
 * ../static/lqg2d_kernel.wasm, which the page carries inline (js_tasks.learner_sources).
 */
#include <stdint.h>
#include <wasm_simd128.h>

__attribute__((import_module("env"), import_name("exp"))) double js_exp(double);
__attribute__((import_module("env"), import_name("log"))) double js_log(double);

#define ZIG_R 3.442619855899

/* What JavaScript writes before a call and reads after it. */
static struct {
    uint32_t kn[128];                 /* the ziggurat's tables, from learner.js: kn (integers */
    double wn[128], fn[128];          /* below 2^31, so the tests on them compare integers), wn, fn */
    double cf[24];                    /* theta, A, B, Q, R (row-major 2 x 2), bs, ba, sigma, gamma */
    uint32_t rng[4];                  /* xoshiro128** state, in and out */
    double found[2];                  /* max |r_t|, max |s_i| over the batch (maxima) */
    double exp2_32[32];               /* 2^(j / 32), from Math.pow (within 1 ulp) */
} io;

__attribute__((export_name("io"))) void *io_address(void) { return &io; }

/* The byte offsets of io's members, in the order of IO_MEMBERS in lqg2d_wasm.js. */
static const int32_t io_members[] = {
    __builtin_offsetof(__typeof__(io), kn),    __builtin_offsetof(__typeof__(io), wn),
    __builtin_offsetof(__typeof__(io), fn),    __builtin_offsetof(__typeof__(io), cf),
    __builtin_offsetof(__typeof__(io), rng),   __builtin_offsetof(__typeof__(io), found),
    __builtin_offsetof(__typeof__(io), exp2_32)};
__attribute__((export_name("io_members"))) const int32_t *io_members_address(void) { return io_members; }

/* ------------------------------------------------------------------ random numbers */
/* xoshiro128**'s state; the hot loop keeps it in locals (a struct in linear memory could alias the output). */
typedef struct { uint32_t a, b, c, d; } Xoshiro;

static inline uint32_t rotl(uint32_t v, int k) { return (v << k) | (v >> (32 - k)); }

static inline uint32_t next_u32(Xoshiro *x) {
    const uint32_t r = rotl(x->b * 5u, 7) * 9u, t = x->b << 9;
    x->c ^= x->a; x->d ^= x->b; x->b ^= x->c; x->a ^= x->d; x->c ^= t; x->d = rotl(x->d, 11);
    return r;
}

/* Rng.prototype.uniform: 53 random bits from two outputs, the first the high part. */
static double uniform(Xoshiro *x) {
    const double hi = (double)(next_u32(x) >> 5);
    const double lo = (double)(next_u32(x) >> 6);
    return (hi * 67108864.0 + lo) / 9007199254740992.0;
}

/*
 * Whether level < exp(y) for y in [-0.5 ZIG_R^2, 0], as JavaScript's Math.exp decides it, mostly
 * without calling it (a call out of WebAssembly costs as much as fifty normals). With
 * y = (32 m + j) ln2 / 32 + r, |r| <= ln2 / 64, e = 2^m 2^(j/32) (1 + r + ... + r^5 / 5!) is within
 * 1e-14 of exp(y), relative (the Taylor remainder is below 3e-15; the table is Math.pow's, within
 * 1 ulp; ln2 / 32 in two parts, 2^m exact), and Math.exp within 1 ulp: outside e (1 -+ 1e-12)
 * the answer is certain. Inside it, which is about never, Math.exp decides.
 */
static int below_exp(double level, double y) {
    static const double LN2_32_HI = 6.93147180369123816490e-01 / 32, LN2_32_LO = 1.90821492927058770002e-10 / 32;
    const double kf = __builtin_rint(y * (32 * 1.44269504088896338700));
    const double r = (y - kf * LN2_32_HI) - kf * LN2_32_LO;
    const int k = (int)kf, j = k & 31, m = (k - j) / 32; /* k = 32 m + j, 0 <= j < 32 */
    const double p = 1.0 + r * (1.0 + r * (0.5 + r * (1.0 / 6 + r * (1.0 / 24 + r * (1.0 / 120)))));
    double e = io.exp2_32[j] * p;
    for (int i = m; i < 0; i++) e *= 0.5;
    if (level < e * (1.0 - 1e-12)) return 1;
    if (level > e * (1.0 + 1e-12)) return 0;
    return level < js_exp(y);
}

/* Math.abs(hz) < kn[iz], the ziggurat's test for a draw inside layer iz's rectangle: |hz| as an
 * unsigned integer (2^31 included) against kn's integers, the same answer as JavaScript's doubles. */
static inline int inside(int32_t hz, int iz) {
    return (hz < 0 ? 0u - (uint32_t)hz : (uint32_t)hz) < io.kn[iz];
}

/* Rng.prototype._zigSlow: the wedges and the tail (about 2.7% of the draws). */
__attribute__((noinline)) static double zig_slow(Xoshiro *x, int32_t hz, int iz) {
    for (;;) {
        const double v = (double)hz * io.wn[iz];
        if (iz == 0) {
            double xt, y;
            do {
                xt = -js_log(1.0 - uniform(x)) / ZIG_R;
                y = -js_log(1.0 - uniform(x));
            } while (y + y < xt * xt);
            return hz > 0 ? ZIG_R + xt : -ZIG_R - xt;
        }
        if (below_exp(io.fn[iz] + uniform(x) * (io.fn[iz - 1] - io.fn[iz]), -0.5 * v * v)) return v;
        hz = (int32_t)next_u32(x);
        iz = (int)(next_u32(x) & 127u);
        if (inside(hz, iz)) return (double)hz * io.wn[iz];
    }
}

/* Rng.prototype.fillNormal(out, 0, count): one output gives four normals their layers. */
static void fill_normal(Xoshiro *state, double *restrict out, int count) {
    Xoshiro x = *state;
    const double *restrict wn = io.wn;
    uint32_t layers = 0;
    int left = 0;
    for (int i = 0; i < count; i++) {
        if (left == 0) { layers = next_u32(&x); left = 4; }
        const int iz = (int)(layers & 127u);
        layers >>= 8; left -= 1;
        const int32_t hz = (int32_t)next_u32(&x);
        if (inside(hz, iz)) {
            out[i] = (double)hz * wn[iz];
        } else {
            Xoshiro spill = x;
            out[i] = zig_slow(&spill, hz, iz);
            x = spill;
        }
    }
    *state = x;
}

/* ---------------------------------------------------------------------- the batch */
/* One trajectory's fields, lane l of a pair block: field f at block[2 * f + l]. */
enum { X0, X1, G0, G1, G2, G3, C0, C1, C2, C3, S0, S1, S2, S3, RET, FIELDS };

/* The batch's constants, as doubles and as both-lane vectors: locals, so that no store to the
 * trajectories can make the compiler load them again. */
typedef struct {
    double c[24]; /* io.cf: k00 k01 k10 k11, A, B, Q, R, bs, ba, sigma, gamma */
    double nbs, nba, iv;
    v128_t v[24], vnbs, vnba, viv, zero, half;
} Consts;

static Consts consts(void) {
    Consts k;
    for (int i = 0; i < 24; i++) { k.c[i] = io.cf[i]; k.v[i] = wasm_f64x2_splat(io.cf[i]); }
    k.nbs = -k.c[20]; k.nba = -k.c[21]; k.iv = 1.0 / (k.c[22] * k.c[22]);
    k.vnbs = wasm_f64x2_splat(k.nbs); k.vnba = wasm_f64x2_splat(k.nba); k.viv = wasm_f64x2_splat(k.iv);
    k.zero = wasm_f64x2_splat(0.0); k.half = wasm_f64x2_splat(-0.5);
    return k;
}

/* Math.max(m, v) for m >= 0, v >= 0 or NaN: NaN wins, as in JavaScript. */
static inline double js_max(double m, double v) { return (v != v || m != m) ? v + m : (v > m ? v : m); }

typedef struct { double n[4], d[4], rmax, fmax; } Sums;

/* One step of one trajectory (lane l of the pair block p), in run2gb's order. */
static inline void step_one(const Consts *k, double *restrict p, int l, double z0, double z1, const double b[4],
                            double disc, int maxima, Sums *acc) {
    const double *cf = k->c;
    const double bs = cf[20], ba = cf[21], sg = cf[22], nbs = k->nbs, nba = k->nba, iv = k->iv;
    const double x0 = p[2 * X0 + l], x1 = p[2 * X1 + l];
    const double h0 = p[2 * G0 + l], h1 = p[2 * G1 + l], h2 = p[2 * G2 + l], h3 = p[2 * G3 + l];
    p[2 * C0 + l] += h0 * b[0]; p[2 * C1 + l] += h1 * b[1]; p[2 * C2 + l] += h2 * b[2]; p[2 * C3 + l] += h3 * b[3];
    const double m0 = 0.0 + cf[0] * x0 + cf[1] * x1, m1 = 0.0 + cf[2] * x0 + cf[3] * x1;
    const double a0 = m0 + sg * z0, a1 = m1 + sg * z1;
    double u0 = a0 < nba ? nba : a0, u1 = a1 < nba ? nba : a1;
    u0 = ba < u0 ? ba : u0; u1 = ba < u1 ? ba : u1;
    double cost = 0.0 + (x0 * cf[12] * x0 + u0 * cf[16] * u0);
    cost += x0 * cf[13] * x1 + u0 * cf[17] * u1;
    cost += x1 * cf[14] * x0 + u1 * cf[18] * u0;
    cost += x1 * cf[15] * x1 + u1 * cf[19] * u1;
    const double dr = -0.5 * cost * disc;
    p[2 * RET + l] += dr;
    if (maxima) {
        const double r = -0.5 * cost;
        acc->rmax = js_max(acc->rmax, r < 0 ? -r : r);
        acc->fmax = js_max(js_max(acc->fmax, x0 < 0 ? -x0 : x0), x1 < 0 ? -x1 : x1);
    }
    const double e0 = iv * (u0 - m0), e1 = iv * (u1 - m1);
    const double g[4] = {h0 + e0 * x0, h1 + e0 * x1, h2 + e1 * x0, h3 + e1 * x1};
    for (int q = 0; q < 4; q++) {
        p[2 * (G0 + q) + l] = g[q];
        p[2 * (S0 + q) + l] += g[q] * dr;
        const double sq = g[q] * g[q];
        acc->n[q] += sq * dr;
        acc->d[q] += sq;
    }
    const double y0 = 0.0 + (cf[4] * x0 + cf[8] * u0) + (cf[5] * x1 + cf[9] * u1);
    const double y1 = 0.0 + (cf[6] * x0 + cf[10] * u0) + (cf[7] * x1 + cf[11] * u1);
    const double w0 = y0 < nbs ? nbs : y0, w1 = y1 < nbs ? nbs : y1;
    p[2 * X0 + l] = bs < w0 ? bs : w0;
    p[2 * X1 + l] = bs < w1 ? bs : w1;
}

#define ADD wasm_f64x2_add
#define MUL wasm_f64x2_mul
#define MAXIMA_LANE(LANE)                                                                  \
    do {                                                                                   \
        const double rl = wasm_f64x2_extract_lane(r, LANE);                                \
        const double s0 = wasm_f64x2_extract_lane(x0, LANE), s1 = wasm_f64x2_extract_lane(x1, LANE); \
        acc->rmax = js_max(acc->rmax, rl < 0 ? -rl : rl);                                  \
        acc->fmax = js_max(js_max(acc->fmax, s0 < 0 ? -s0 : s0), s1 < 0 ? -s1 : s1);       \
    } while (0)

/* One step of two trajectories (both lanes of p): step_one on each lane at once. */
static inline void step_pair(const Consts *k, v128_t *restrict p, const double *z0, const double *z1,
                             const v128_t bv[4], v128_t vdisc, int maxima, Sums *acc) {
    const v128_t *K = k->v, zero = k->zero;
    const v128_t x0 = p[X0], x1 = p[X1];
    const v128_t h[4] = {p[G0], p[G1], p[G2], p[G3]};
    for (int q = 0; q < 4; q++) p[C0 + q] = ADD(p[C0 + q], MUL(h[q], bv[q]));
    const v128_t m0 = ADD(ADD(zero, MUL(K[0], x0)), MUL(K[1], x1));
    const v128_t m1 = ADD(ADD(zero, MUL(K[2], x0)), MUL(K[3], x1));
    const v128_t a0 = ADD(m0, MUL(K[22], wasm_v128_load(z0))), a1 = ADD(m1, MUL(K[22], wasm_v128_load(z1)));
    const v128_t u0 = wasm_f64x2_pmin(wasm_f64x2_pmax(a0, k->vnba), K[21]);
    const v128_t u1 = wasm_f64x2_pmin(wasm_f64x2_pmax(a1, k->vnba), K[21]);
    v128_t cost = ADD(zero, ADD(MUL(MUL(x0, K[12]), x0), MUL(MUL(u0, K[16]), u0)));
    cost = ADD(cost, ADD(MUL(MUL(x0, K[13]), x1), MUL(MUL(u0, K[17]), u1)));
    cost = ADD(cost, ADD(MUL(MUL(x1, K[14]), x0), MUL(MUL(u1, K[18]), u0)));
    cost = ADD(cost, ADD(MUL(MUL(x1, K[15]), x1), MUL(MUL(u1, K[19]), u1)));
    const v128_t r = MUL(k->half, cost), dr = MUL(r, vdisc);
    p[RET] = ADD(p[RET], dr);
    if (maxima) { MAXIMA_LANE(0); MAXIMA_LANE(1); }
    const v128_t e0 = MUL(k->viv, wasm_f64x2_sub(u0, m0)), e1 = MUL(k->viv, wasm_f64x2_sub(u1, m1));
    const v128_t g[4] = {ADD(h[0], MUL(e0, x0)), ADD(h[1], MUL(e0, x1)), ADD(h[2], MUL(e1, x0)),
                         ADD(h[3], MUL(e1, x1))};
    for (int q = 0; q < 4; q++) {
        p[G0 + q] = g[q];
        p[S0 + q] = ADD(p[S0 + q], MUL(g[q], dr));
        const v128_t sq = MUL(g[q], g[q]), nd = MUL(sq, dr);
        acc->n[q] += wasm_f64x2_extract_lane(nd, 0);
        acc->n[q] += wasm_f64x2_extract_lane(nd, 1);
        acc->d[q] += wasm_f64x2_extract_lane(sq, 0);
        acc->d[q] += wasm_f64x2_extract_lane(sq, 1);
    }
    const v128_t y0 = ADD(ADD(zero, ADD(MUL(K[4], x0), MUL(K[8], u0))), ADD(MUL(K[5], x1), MUL(K[9], u1)));
    const v128_t y1 = ADD(ADD(zero, ADD(MUL(K[6], x0), MUL(K[10], u0))), ADD(MUL(K[7], x1), MUL(K[11], u1)));
    p[X0] = wasm_f64x2_pmin(wasm_f64x2_pmax(y0, k->vnbs), K[20]);
    p[X1] = wasm_f64x2_pmin(wasm_f64x2_pmax(y1, k->vnbs), K[20]);
}
#undef ADD
#undef MUL

/*
 * A batch of n trajectories of H steps: the initial states uniform in [-bs, bs) and every
 * normal drawn from io.rng's state, in the JavaScript's order (rngSource's init, then
 * fillNormal(z, 0, 2 n) at each step). z (2 n doubles) is scratch; st (FIELDS * 2 doubles per
 * pair of trajectories, 16-byte aligned) holds the trajectories. Writes the gradient samples
 * (4 x n, component-major) and the discounted returns (n); io.rng comes back advanced.
 */
__attribute__((export_name("lqg2_gpomdp_baseline")))
void lqg2_gpomdp_baseline(int n, int H, int maxima, double *restrict z, v128_t *restrict st,
                          double *restrict samples, double *restrict returns) {
    const int pairs = n / 2, odd = n & 1, blocks = pairs + odd;
    const Consts k = consts();
    Xoshiro rng = {io.rng[0], io.rng[1], io.rng[2], io.rng[3]};
    for (int i = 0; i < blocks * FIELDS; i++) st[i] = k.zero;
    const double lo = -k.c[20], hi = k.c[20];
    for (int j = 0; j < n; j++) {
        double *p = (double *)(st + (j / 2) * FIELDS);
        p[2 * X0 + (j & 1)] = lo + (hi - lo) * uniform(&rng);
        p[2 * X1 + (j & 1)] = lo + (hi - lo) * uniform(&rng);
    }
    double b[4] = {0, 0, 0, 0}, disc = 1.0;
    Sums sums = {{0, 0, 0, 0}, {0, 0, 0, 0}, 0, 0};
    for (int t = 0; t < H; t++) {
        fill_normal(&rng, z, 2 * n);
        for (int q = 0; q < 4; q++) sums.n[q] = sums.d[q] = 0.0;
        const v128_t bv[4] = {wasm_f64x2_splat(b[0]), wasm_f64x2_splat(b[1]), wasm_f64x2_splat(b[2]),
                              wasm_f64x2_splat(b[3])};
        const v128_t vdisc = wasm_f64x2_splat(disc);
        for (int i = 0; i < pairs; i++) step_pair(&k, st + i * FIELDS, z + 2 * i, z + n + 2 * i, bv, vdisc, maxima, &sums);
        if (odd) step_one(&k, (double *)(st + pairs * FIELDS), 0, z[n - 1], z[2 * n - 1], b, disc, maxima, &sums);
        for (int q = 0; q < 4; q++) b[q] = sums.d[q] != 0 ? sums.n[q] / sums.d[q] : 0;
        disc *= k.c[23];
    }
    /* run2gb's closing pass: the last step's baseline term, then the component-major rows. */
    for (int j = 0; j < n; j++) {
        const double *p = (const double *)(st + (j / 2) * FIELDS);
        const int l = j & 1;
        for (int q = 0; q < 4; q++) samples[q * n + j] = p[2 * (S0 + q) + l] - (p[2 * (C0 + q) + l] + p[2 * (G0 + q) + l] * b[q]);
        returns[j] = p[2 * RET + l];
    }
    io.found[0] = sums.rmax; io.found[1] = sums.fmax;
    io.rng[0] = rng.a; io.rng[1] = rng.b; io.rng[2] = rng.c; io.rng[3] = rng.d;
}

/* below_exp, for tests/test_wasm_kernel.py: it must answer as level < Math.exp(y) does. */
__attribute__((export_name("below_exp"))) int below_exp_export(double level, double y) { return below_exp(level, y); }
