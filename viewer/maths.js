// hdr4d viewer, the maths (no WebGL): the embedded .ply and tone tables, the 4D rotation and
// covariance, the SH basis and the baked tone curves, as the project's renderer computes them
// (method/gaussian/, method/run/tone_tables.h). splats.js uses them for each frame.
'use strict';
(function () {
  const MAX_LOG_RADIANCE = 30;     // exp is evaluated at min(c, 30), as the renderer does
  const CULL_MARGINAL = 0.05;      // a Gaussian is skipped when p(t) <= this
  const SH_C0 = 0.28209479177387814;
  const SH_C1 = 0.4886025119029199;
  const SH_C2 = [1.0925484305920792, -1.0925484305920792, 0.31539156525252005,
    -1.0925484305920792, 0.5462742152960396];
  const SH_C3 = [-0.5900435899266435, 2.890611442640554, -0.4570457994644658,
    0.3731763325901154, -0.4570457994644658, 1.445305721320277, -0.5900435899266435];

  function base64Bytes(text) {
    const s = atob(text.trim());
    const out = new Uint8Array(s.length);
    for (let i = 0; i < s.length; ++i) out[i] = s.charCodeAt(i);
    return out;
  }

  // The 4D .ply (docs/hdr-ply.md): header comments "hdr4d-<key> numbers...", float columns.
  function parsePly(bytes) {
    const head = new TextDecoder().decode(bytes.subarray(0, Math.min(bytes.length, 1 << 16)));
    const end = head.indexOf('end_header\n');
    if (end < 0) throw new Error('the embedded .ply has no end_header');
    const columns = [], comments = {};
    let count = 0;
    for (const line of head.slice(0, end).split('\n')) {
      const w = line.trim().split(/\s+/);
      if (w[0] === 'comment' && w[1] && w[1].startsWith('hdr4d-')) {
        comments[w[1].replace(/:$/, '')] = w.slice(2);
      } else if (w[0] === 'element') {
        count = parseInt(w[2], 10);
      } else if (w[0] === 'property') {
        columns.push(w[2]);
      }
    }
    const offset = new TextEncoder().encode(head.slice(0, end + 'end_header\n'.length)).length;
    const body = new Float32Array(bytes.slice(offset, offset + count * columns.length * 4).buffer);
    const index = {};
    columns.forEach((name, k) => { index[name] = k; });
    return { columns, index, comments, count, body, stride: columns.length };
  }

  function normalised(q) {
    const n = Math.hypot(q[0], q[1], q[2], q[3]);
    return n > 1e-12 ? q.map((v) => v / n) : [1, 0, 0, 0];
  }

  // R = (M_l(q_l) M_r(q_r)) with rows and columns reversed, as method/gaussian/rotation4d.h.
  function rotation4(ql, qr) {
    const [a, b, c, d] = normalised(ql), [p, x, y, z] = normalised(qr);
    const L = [[a, -b, -c, -d], [b, a, -d, c], [c, d, a, -b], [d, -c, b, a]];
    const Rr = [[p, x, y, z], [-x, p, -z, y], [-y, z, p, -x], [-z, -y, x, p]];
    const R = [[0, 0, 0, 0], [0, 0, 0, 0], [0, 0, 0, 0], [0, 0, 0, 0]];
    for (let i = 0; i < 4; ++i) {
      for (let j = 0; j < 4; ++j) {
        let s = 0;
        for (let k = 0; k < 4; ++k) s += L[3 - i][k] * Rr[k][3 - j];
        R[i][j] = s;
      }
    }
    return R;
  }

  function rotation3(q) {
    const [w, x, y, z] = normalised(q);
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
      [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
      [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]];
  }

  // Sigma = R diag(exp(2 s)) R^T, as its upper triangle in row order.
  function covariance(R, logScales) {
    const n = R.length, out = [];
    for (let i = 0; i < n; ++i) {
      for (let j = i; j < n; ++j) {
        let s = 0;
        for (let k = 0; k < n; ++k) s += R[i][k] * R[j][k] * Math.exp(2 * logScales[k]);
        out.push(s);
      }
    }
    return out;
  }

  // The Gaussians with what does not depend on the view: 4D covariance (10 values, upper
  // triangle of xyzt) or 3D (6), opacity, colour coefficients coefficient-major.
  function prepareModel(ply) {
    const c = ply.comments, ix = ply.index, s = ply.stride, b = ply.body;
    const basis = c['hdr4d-basis'].map(Number);
    const m = {
      n: ply.count, temporal: c['hdr4d-temporal'][0] === '1',
      logHdr: c['hdr4d-colour'][0] === 'log-hdr', shDegree: basis[0], timeDegree: basis[1],
      duration: Number(c['hdr4d-time-duration'][0]),
    };
    m.functions = (m.shDegree + 1) * (m.shDegree + 1);
    m.coefficients = m.functions * (m.timeDegree + 1);
    if (!m.temporal) m.timeDegree = 0;
    m.mean = new Float64Array(m.n * 4);
    m.cov = new Float64Array(m.n * 10);
    m.opacity = new Float64Array(m.n);
    m.coeff = new Float64Array(m.n * m.coefficients * 3);
    m.headOffset = ix.hdr_offset_0 !== undefined ? new Float64Array(m.n * 3) : null;
    const rest = m.coefficients - 1;
    for (let i = 0; i < m.n; ++i) {
      const row = (name) => b[i * s + ix[name]];
      const q = (p) => [row(p + 0), row(p + 1), row(p + 2), row(p + 3)];
      for (let a = 0; a < 4; ++a) m.mean[i * 4 + a] = row(['x', 'y', 'z', 't'][a]);
      const ls = [row('scale_0'), row('scale_1'), row('scale_2'), row('scale_3')];
      const cov = m.temporal ? covariance(rotation4(q('rot_'), q('rotr_')), ls)
        : covariance(rotation3(q('rot_')), ls.slice(0, 3));
      for (let k = 0; k < cov.length; ++k) m.cov[i * 10 + k] = cov[k];
      m.opacity[i] = 1 / (1 + Math.exp(-row('opacity')));
      for (let ch = 0; ch < 3; ++ch) {
        m.coeff[(i * m.coefficients) * 3 + ch] = row('f_dc_' + ch);
        for (let k = 1; k <= rest; ++k)
          m.coeff[(i * m.coefficients + k) * 3 + ch] = row('f_rest_' + (ch * rest + k - 1));
        if (m.headOffset) m.headOffset[i * 3 + ch] = row('hdr_offset_' + ch);
      }
    }
    return m;
  }

  // Y_lm(d) for l <= degree, 3DGS order and signs (method/gaussian/sh4d.h).
  function shBasis(x, y, z, degree, out) {
    out[0] = SH_C0;
    if (degree < 1) return;
    out[1] = -SH_C1 * y; out[2] = SH_C1 * z; out[3] = -SH_C1 * x;
    if (degree < 2) return;
    const xx = x * x, yy = y * y, zz = z * z, xy = x * y, yz = y * z, xz = x * z;
    out[4] = SH_C2[0] * xy; out[5] = SH_C2[1] * yz; out[6] = SH_C2[2] * (2 * zz - xx - yy);
    out[7] = SH_C2[3] * xz; out[8] = SH_C2[4] * (xx - yy);
    if (degree < 3) return;
    out[9] = SH_C3[0] * y * (3 * xx - yy); out[10] = SH_C3[1] * xy * z;
    out[11] = SH_C3[2] * y * (4 * zz - xx - yy); out[12] = SH_C3[3] * z * (2 * zz - 3 * xx - 3 * yy);
    out[13] = SH_C3[4] * x * (4 * zz - xx - yy); out[14] = SH_C3[5] * z * (xx - yy);
    out[15] = SH_C3[6] * x * (xx - 3 * yy);
  }

  // The baked tone curves (method/run/tone_tables.h): linear in log-HDR and in log exposure,
  // held at the ends (LookUpToneTables).
  function toneLookup(tone, row, logE, x, c) {
    const le = tone.log_exposures, ne = le.length;
    let e0 = 0, we = 0;
    if (ne > 1 && logE > le[0]) {
      if (logE >= le[ne - 1]) e0 = ne - 1;
      else {
        while (le[e0 + 1] <= logE) ++e0;
        we = (logE - le[e0]) / (le[e0 + 1] - le[e0]);
      }
    }
    const u = Math.min(Math.max((x - tone.x0) / (tone.x1 - tone.x0), 0), 1) * (tone.nodes - 1);
    const k0 = Math.min(Math.floor(u), tone.nodes - 2), wk = u - k0;
    const at = (e) => {
      const base = ((row * ne + e) * tone.nodes + k0) * 3 + c;
      return (1 - wk) * tone.values[base] + wk * tone.values[base + 3];
    };
    const v0 = at(e0);
    return we > 0 ? (1 - we) * v0 + we * at(e0 + 1) : v0;
  }

  // The radiance-bank row of a time in [0, 1] (RadianceBank::TimeIndex).
  function timeIndex(t, numTimes) {
    if (!(t > 0)) return 0;
    if (t >= 1) return numTimes - 1;
    return Math.min(Math.floor(t * numTimes), numTimes - 1);
  }

  window.hdr4dViewerMaths = { base64Bytes, parsePly, prepareModel, shBasis, toneLookup, timeIndex };
})();
