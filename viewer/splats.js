// hdr4d viewer, one frame on the CPU: each Gaussian sliced at the time (conditional mean and
// covariance given t, marginal p(t) into the opacity, culled at p(t) <= 0.05 or in front of the
// near plane), its colour from the SH x time basis seen from the camera, then through the baked
// tone curves (LDR) or exp (HDR); sorted far to near for the blend. The projection and the blend
// run in the shaders (gl.js).
'use strict';
(function () {
  const M = window.hdr4dViewerMaths;
  const NEAR = 0.2;
  const FLOATS = 13;  // per splat: mean (3), covariance (6), colour (3), opacity

  // The 3D Gaussian of row i at time t into out[0..9]: mean, covariance (upper triangle), p(t).
  function slice(m, i, t, out) {
    const c = m.cov, o = i * 10, mu = m.mean;
    if (!m.temporal) {
      out[0] = mu[i * 4]; out[1] = mu[i * 4 + 1]; out[2] = mu[i * 4 + 2];
      for (let k = 0; k < 6; ++k) out[3 + k] = c[o + k];
      out[9] = 1;
      return;
    }
    // Upper triangle of the 4x4, row order: 00 01 02 03 11 12 13 22 23 33.
    const s0 = c[o + 3], s1 = c[o + 6], s2 = c[o + 8];
    const trace = c[o] + c[o + 4] + c[o + 7] + c[o + 9];
    const floor = 1e-12 * trace + 1e-30;
    const stt = c[o + 9] > floor ? c[o + 9] : floor;
    const dt = t - mu[i * 4 + 3], inv = 1 / stt;
    out[0] = mu[i * 4] + s0 * dt * inv;
    out[1] = mu[i * 4 + 1] + s1 * dt * inv;
    out[2] = mu[i * 4 + 2] + s2 * dt * inv;
    out[3] = c[o] - s0 * s0 * inv; out[4] = c[o + 1] - s0 * s1 * inv; out[5] = c[o + 2] - s0 * s2 * inv;
    out[6] = c[o + 4] - s1 * s1 * inv; out[7] = c[o + 5] - s1 * s2 * inv;
    out[8] = c[o + 7] - s2 * s2 * inv;
    out[9] = Math.exp(-0.5 * dt * dt * inv);
  }

  // The colour basis weights of one Gaussian (sh4d.h EvalColorBasisWeights): Y_lm(d) times
  // cos(2 pi n dt / T) for each time block n.
  function basisWeights(m, dx, dy, dz, dt, w) {
    const norm = Math.hypot(dx, dy, dz);
    w.fill(0);
    if (norm > 0) M.shBasis(dx / norm, dy / norm, dz / norm, m.shDegree, w);
    else w[0] = 0.28209479177387814;
    if (m.timeDegree === 0) return;
    const c1 = Math.cos(2 * Math.PI * dt / m.duration);
    let prev = 1, cn = c1;
    for (let n = 1; n <= m.timeDegree; ++n) {
      for (let lm = 0; lm < m.functions; ++lm) w[n * m.functions + lm] = w[lm] * cn;
      const next = 2 * c1 * cn - prev;
      prev = cn; cn = next;
    }
  }

  // The display colour of a value c (SH x time value + 0.5) in channel ch, for the view's output.
  function shade(view, m, i, value, ch) {
    if (!m.logHdr) return Math.max(value, 0);
    if (view.mode === 'hdr') {
      const head = m.headOffset ? m.headOffset[i * 3 + ch] : 0;
      return Math.exp(Math.min(value + head, 30)) * view.hdrScale;
    }
    return M.toneLookup(view.tone, view.toneRow, view.logExposure, value, ch);
  }

  // Fills `frame` (Float32Array, FLOATS per splat, far to near) for `view`: camera {R (row-major
  // cam_from_world, OpenCV axes), t}, time, mode ('ldr' | 'hdr'), tone, toneRow, logExposure,
  // hdrScale. Returns the number of splats.
  function buildFrame(m, view, frame) {
    const R = view.camera.R, T = view.camera.t;
    // Camera centre C = -R^T t.
    const C = [0, 1, 2].map((j) => -(R[j] * T[0] + R[3 + j] * T[1] + R[6 + j] * T[2]));
    const g = new Float64Array(10), w = new Float64Array(m.coefficients);
    const depth = new Float32Array(m.n), rows = new Float32Array(m.n * FLOATS);
    const order = [];
    for (let i = 0; i < m.n; ++i) {
      slice(m, i, view.time, g);
      if (!(g[9] > 0.05)) continue;
      const z = R[6] * g[0] + R[7] * g[1] + R[8] * g[2] + T[2];
      if (!(z > NEAR)) continue;
      basisWeights(m, g[0] - C[0], g[1] - C[1], g[2] - C[2], m.mean[i * 4 + 3] - view.time, w);
      const r = order.length * FLOATS;
      for (let k = 0; k < 9; ++k) rows[r + k] = g[k];
      for (let ch = 0; ch < 3; ++ch) {
        let v = 0.5;
        const base = i * m.coefficients * 3 + ch;
        for (let k = 0; k < m.coefficients; ++k) v += w[k] * m.coeff[base + k * 3];
        rows[r + 9 + ch] = shade(view, m, i, v, ch);
      }
      rows[r + 12] = m.opacity[i] * g[9];
      depth[order.length] = z;
      order.push(order.length);
    }
    order.sort((a, b) => depth[b] - depth[a]);
    for (let k = 0; k < order.length; ++k)
      frame.set(rows.subarray(order[k] * FLOATS, order[k] * FLOATS + FLOATS), k * FLOATS);
    return order.length;
  }

  window.hdr4dViewerSplats = { buildFrame, FLOATS };
})();
