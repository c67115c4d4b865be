#!/usr/bin/env python3
# xmath_gen.py - derives the constants, tables and polynomial coefficients of
# common/xmath.c (needs mpmath; not part of the build: run it by hand and
# paste its output when an approximation changes).
#
# Polynomials interpolate the target at Chebyshev nodes of its interval (a
# near-minimax fit); the script prints the largest relative error of each
# fit, sampled on a dense grid, which docs/maths.md quotes.
from mpmath import mp, mpf, sin, cos, atan, exp, log, log1p, pi, ln2, chebyt, matrix, lu_solve, sqrt, floor, ldexp

mp.prec = 1600


def dbl(v):
    return float(v)


def hexd(v):
    return float(v).hex()


def split(v, bits):
    """v rounded to `bits` significant bits, then the rest rounded to double."""
    e = int(floor(mp.log(abs(v), 2)))
    hi = mp.nint(v * mpf(2) ** (bits - 1 - e)) / mpf(2) ** (bits - 1 - e)
    return hi, v - hi


def fit(g, a, b, n):
    """coefficients c0..c(n-1) of the polynomial interpolating g at n Chebyshev nodes of [a, b]"""
    xs = [(a + b) / 2 + (b - a) / 2 * cos(pi * (2 * k + 1) / (2 * n)) for k in range(n)]
    A = matrix(n, n)
    y = matrix(n, 1)
    for i, x in enumerate(xs):
        for j in range(n):
            A[i, j] = x ** j
        y[i] = g(x)
    c = lu_solve(A, y)
    return [mpf(dbl(c[j])) for j in range(n)]


def horner(c, z):
    r = mpf(0)
    for v in reversed(c):
        r = r * z + v
    return r


def maxrel(f, approx, a, b, n=4000):
    m = mpf(0)
    for k in range(1, n):
        x = a + (b - a) * k / n
        if x == 0:
            continue
        e = abs((approx(x) - f(x)) / f(x))
        m = max(m, e)
    return m


def show(name, c, err):
    print("/* %s: %d coefficients, max relative error of the fit 2^%.1f */" % (name, len(c), float(mp.log(err, 2))))
    print("static const double %s[%d] = { %s };" % (name, len(c), ", ".join(hexd(v) for v in c)))


# sin(x) = x + x^3 S(x^2), |x| <= pi/4
zmax = (pi / 4) ** 2
S = fit(lambda z: (sin(sqrt(z)) - sqrt(z)) / (z * sqrt(z)), mpf(0), zmax, 7)
show("sin_c", S, maxrel(sin, lambda x: x + x ** 3 * horner(S, x * x), mpf(0), pi / 4))
# cos(x) = 1 - x^2/2 + x^4 C(x^2)
C = fit(lambda z: (cos(sqrt(z)) - 1 + z / 2) / (z * z), mpf(0), zmax, 7)
show("cos_c", C, maxrel(cos, lambda x: 1 - x * x / 2 + x ** 4 * horner(C, x * x), mpf(0), pi / 4))
# atan(t) = t + t^3 A(t^2): |t| <= 3.5/64 (no table entry), |t| <= 1/128 (after one)
tm = mpf("3.5") / 64
A = fit(lambda z: (atan(sqrt(z)) - sqrt(z)) / (z * sqrt(z)), mpf(0), tm * tm, 6)
show("atan_c", A, maxrel(atan, lambda t: t + t ** 3 * horner(A, t * t), mpf(0), tm))
tm = mpf(1) / 128
A = fit(lambda z: (atan(sqrt(z)) - sqrt(z)) / (z * sqrt(z)), mpf(0), tm * tm, 3)
show("atan_s", A, maxrel(atan, lambda t: t + t ** 3 * horner(A, t * t), mpf(0), tm))
# asin(x) = x + x^3 P(x^2), |x| <= 1/2
from mpmath import asin
P = fit(lambda z: (asin(sqrt(z)) - sqrt(z)) / (z * sqrt(z)), mpf(0), mpf(1) / 4, 13)
show("asin_c", P, maxrel(asin, lambda x: x + x ** 3 * horner(P, x * x), mpf(0), mpf(1) / 2))
# exp(r) = 1 + r + r^2/2 + r^3 E(r), |r| <= ln2/128
rm = ln2 / 128 * mpf("1.01")
E = fit(lambda r: (exp(r) - 1 - r - r * r / 2) / r ** 3, -rm, rm, 4)
show("exp_c", E, maxrel(lambda r: exp(r) - 1, lambda r: r + r * r / 2 + r ** 3 * horner(E, r), -rm, rm))
# log1p(q) = q - q^2/2 + q^3 L(q), |q| <= 1/256 / (90/128)
qm = mpf(1) / 256 / (mpf(90) / 128) * mpf("1.01")
L = fit(lambda q: (log1p(q) - q + q * q / 2) / q ** 3, -qm, qm, 6)
show("log1p_c", L, maxrel(log1p, lambda q: q - q * q / 2 + q ** 3 * horner(L, q), -qm, qm))


def table(name, vals, comment):
    print("/* %s */" % comment)
    print("static const double %s[%d][2] = {" % (name, len(vals)))
    for v in vals:
        h = mpf(dbl(v))
        print("\t{ %s, %s }," % (hexd(h), hexd(v - h)))
    print("};")


table("exp_tab", [mpf(2) ** (mpf(j) / 64) for j in range(64)], "2^(j/64), j = 0..63, as hi + lo")
table("log_tab", [log(mpf(j) / 128) for j in range(90, 182)], "log(j/128), j = 90..181, as hi + lo")
table("atan_tab", [atan(mpf(i) / 64) for i in range(0, 65)], "atan(i/64), i = 0..64, as hi + lo")
print("/* 128/j, j = 90..181, rounded (log's reciprocals: only the rounding's size matters) */")
print("static const double inv_tab[92] = {")
vals = [hexd(mpf(128) / j) for j in range(90, 182)]
for i in range(0, len(vals), 4):
    print("\t" + ", ".join(vals[i:i + 4]) + ",")
print("};")

# 2/pi as 32-bit words, most significant first (bit 1 of the first word weighs 2^-1)
words = []
v = 2 / pi
for i in range(44):
    v *= 2 ** 32
    w = int(floor(v))
    words.append(w)
    v -= w
print("/* 2/pi in 32-bit words: word i holds the bits of weight 2^-(32i+1) .. 2^-(32i+32) */")
print("static const uint32_t two_over_pi[%d] = {" % len(words))
for i in range(0, len(words), 6):
    print("\t" + ", ".join("0x%08x" % w for w in words[i:i + 6]) + ",")
print("};")


def const(name, v):
    print("static const double %s = %s; /* %s */" % (name, hexd(v), mp.nstr(v, 20)))


p1, r = split(pi / 2, 33)
p2, r = split(r, 33)
const("PIO2_1", p1)
const("PIO2_2", p2)
const("PIO2_3", r)
h = mpf(dbl(pi / 2))
const("PIO2_HI", h)
const("PIO2_LO", pi / 2 - h)
h = mpf(dbl(pi))
const("PI_HI", h)
const("PI_LO", pi - h)
const("TWO_OVER_PI", 2 / pi)
l1, r = split(ln2, 42)
const("LN2_HI", l1)
const("LN2_LO", r)
l1, r = split(ln2 / 64, 36)
const("LN2_64_HI", l1)
const("LN2_64_LO", r)
const("INV_LN2_64", 64 / ln2)
