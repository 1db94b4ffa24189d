#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tools/gen_ziggurat.py — writes drivers/ziggurat_table.h, the 256-layer ziggurat of the
standard normal used by urt_rng_normal (drivers/sensors.c; Marsaglia and Tsang, "The Ziggurat
Method for Generating Random Variables", J. Stat. Softw. 5(8), 2000).

The layers have equal area V. The base layer is the rectangle [0, R] x [0, f(R)] plus the tail
beyond R, f(x) = exp(-x^2/2), so V = R f(R) + sqrt(pi/2) erfc(R/sqrt 2); layer i >= 1 spans
[0, x_i] x [f(x_i), f(x_i+1)] with x_i+1 = f^-1(V/x_i + f(x_i)). R is found here by bisection
so that the top layer (x_255, up to f = 1) has the area V too: the published R = 3.6541528853610088
comes out, with V to double precision (the paper prints V to 12 digits). The table is written
once and checked in, so the sequence of a seed does not depend on the libm that builds urtwin;
tests/drivers/test_sensors.c checks every layer's area with this machine's libm.

    python3 tools/gen_ziggurat.py > drivers/ziggurat_table.h
"""
import math

N = 256


def f(x):
    return math.exp(-0.5 * x * x)


def layers(r):
    """(the top layer's area minus V, V, x_0..x_N) for a base-layer edge r; the area is None
    when the layers reach f = 1 before the top one."""
    v = r * f(r) + math.sqrt(math.pi / 2) * math.erfc(r / math.sqrt(2))
    x = [0.0] * (N + 1)
    x[0], x[1] = v / f(r), r   # x_0: the base layer's width as one rectangle of area V
    for i in range(1, N - 1):
        arg = v / x[i] + f(x[i])
        if arg >= 1.0:
            return None, v, x
        x[i + 1] = math.sqrt(-2.0 * math.log(arg))
    return x[N - 1] * (1.0 - f(x[N - 1])) - v, v, x


def main():
    lo, hi = 3.6, 3.7
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        top, _, _ = layers(mid)
        if top is None or top < 0.0:
            lo = mid
        else:
            hi = mid
    _, v, x = layers(lo)
    fx = [f(t) for t in x]
    fx[N] = 1.0
    out = ["/* SPDX-License-Identifier: Apache-2.0",
           " * drivers/ziggurat_table.h — written by tools/gen_ziggurat.py (do not edit): the",
           " * 256-layer ziggurat of the standard normal for urt_rng_normal. x[i]: layer i's",
           " * right edge (x[0] the base layer's width as one rectangle of area V, x[1] = R,",
           " * x[256] = 0); f[i] = exp(-x[i]^2/2) (f[256] = 1). */",
           "#ifndef URT_DRIVERS_ZIGGURAT_TABLE_H",
           "#define URT_DRIVERS_ZIGGURAT_TABLE_H",
           "",
           f"#define URT_ZIG_R {x[1]!r}",
           f"#define URT_ZIG_V {v!r}",
           ""]
    for name, vals in (("urt_zig_x", x), ("urt_zig_f", fx)):
        out.append(f"static const double {name}[{N + 1}] = {{")
        for k in range(0, N + 1, 3):
            out.append("    " + " ".join(f"{t!r}," for t in vals[k:k + 3]))
        out.append("};")
        out.append("")
    out.append("#endif")
    print("\n".join(out))


if __name__ == "__main__":
    main()
