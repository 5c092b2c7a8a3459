// hdr4d viewer, orbit and start-up: dragging turns the camera about the point the dataset's
// cameras look at (the least-squares meeting point of their optical axes, as `hdr4d render
// --video` orbits) around their mean up axis and its own right axis; the wheel moves it towards
// or away from that point. Then the hash picks the first view and the page renders it.
'use strict';
(function () {
  const P = window.hdr4dViewerPage;
  const cameras = P.data.cameras;

  // Rows of R (cam_from_world, OpenCV): x right, y down, z forward, in world coordinates.
  const row = (R, r) => [R[3 * r], R[3 * r + 1], R[3 * r + 2]];
  const centre = (c) => [0, 1, 2].map((j) => -(c.R[j] * c.t[0] + c.R[3 + j] * c.t[1] + c.R[6 + j] * c.t[2]));

  // argmin_p sum_i |(I - d_i d_i^T)(p - c_i)|^2, by Cramer's rule; null when the axes are parallel.
  function meetingPoint() {
    const A = [0, 0, 0, 0, 0, 0, 0, 0, 0], b = [0, 0, 0];
    for (const cam of cameras) {
      const d = row(cam.R, 2), c = centre(cam);
      for (let i = 0; i < 3; ++i) {
        for (let j = 0; j < 3; ++j) {
          const m = (i === j ? 1 : 0) - d[i] * d[j];
          A[3 * i + j] += m;
          b[i] += m * c[j];
        }
      }
    }
    const det = (M) => M[0] * (M[4] * M[8] - M[5] * M[7]) - M[1] * (M[3] * M[8] - M[5] * M[6]) +
      M[2] * (M[3] * M[7] - M[4] * M[6]);
    const D = det(A);
    if (!(Math.abs(D) > 1e-9)) return null;
    return [0, 1, 2].map((k) => det(A.map((v, idx) => (idx % 3 === k ? b[Math.floor(idx / 3)] : v))) / D);
  }
  const target = meetingPoint() || [0, 0, 0];
  const up = (() => {
    const u = [0, 0, 0];
    for (const cam of cameras) row(cam.R, 1).forEach((v, k) => { u[k] -= v; });
    const n = Math.hypot(...u);
    return n > 0 ? u.map((v) => v / n) : [0, 0, 1];
  })();

  // Rotation by `angle` about unit `axis` (Rodrigues), row-major.
  function axisRotation(axis, angle) {
    const [x, y, z] = axis, c = Math.cos(angle), s = Math.sin(angle), t = 1 - c;
    return [t * x * x + c, t * x * y - s * z, t * x * z + s * y,
      t * x * y + s * z, t * y * y + c, t * y * z - s * x,
      t * x * z - s * y, t * y * z + s * x, t * z * z + c];
  }
  const mul = (A, B) => [0, 1, 2, 3, 4, 5, 6, 7, 8].map((k) => {
    const i = Math.floor(k / 3), j = k % 3;
    return A[3 * i] * B[j] + A[3 * i + 1] * B[3 + j] + A[3 * i + 2] * B[6 + j];
  });
  const transpose = (A) => [A[0], A[3], A[6], A[1], A[4], A[7], A[2], A[5], A[8]];

  // Turns the world by Q about the target: the camera's centre moves, its R becomes R Q^T.
  function turn(Q) {
    const cam = P.state.camera, c = centre(cam);
    const rel = c.map((v, k) => v - target[k]);
    const moved = [0, 1, 2].map((i) => target[i] + Q[3 * i] * rel[0] + Q[3 * i + 1] * rel[1] + Q[3 * i + 2] * rel[2]);
    cam.R = mul(cam.R, transpose(Q));
    cam.t = [0, 1, 2].map((i) => -(cam.R[3 * i] * moved[0] + cam.R[3 * i + 1] * moved[1] + cam.R[3 * i + 2] * moved[2]));
  }

  function zoom(factor) {
    const cam = P.state.camera, c = centre(cam);
    const moved = c.map((v, k) => target[k] + (v - target[k]) * factor);
    cam.t = [0, 1, 2].map((i) => -(cam.R[3 * i] * moved[0] + cam.R[3 * i + 1] * moved[1] + cam.R[3 * i + 2] * moved[2]));
  }

  function setupMouse(canvas) {
    let last = null;
    canvas.addEventListener('pointerdown', (e) => { last = [e.clientX, e.clientY]; canvas.setPointerCapture(e.pointerId); });
    canvas.addEventListener('pointerup', () => { last = null; });
    canvas.addEventListener('pointermove', (e) => {
      if (!last) return;
      const dx = e.clientX - last[0], dy = e.clientY - last[1];
      last = [e.clientX, e.clientY];
      turn(mul(axisRotation(row(P.state.camera.R, 0), -dy * 0.005), axisRotation(up, -dx * 0.005)));
      P.render();
    });
    canvas.addEventListener('wheel', (e) => {
      e.preventDefault();
      zoom(Math.exp(e.deltaY * 0.001));
      P.render();
    }, { passive: false });
  }

  // #camera=<split>:<index>&time=<t>&exposure=<seconds>&mode=ldr|hdr&ui=0
  function applyHash() {
    const q = new URLSearchParams(location.hash.replace(/^#/, ''));
    let k = cameras.findIndex((c) => c.split === 'test');
    if (k < 0) k = 0;
    if (q.has('camera')) {
      const [split, index] = q.get('camera').split(':');
      const found = cameras.findIndex((c) => c.split === split && c.index === Number(index));
      if (found < 0) throw new Error(`no camera ${q.get('camera')} in this run's dataset`);
      k = found;
    }
    if (cameras.length === 0) throw new Error('the run\'s dataset has no cameras');
    P.pickCamera(k);
    document.getElementById('camera').value = k;
    if (q.has('time')) P.state.time = Math.min(Math.max(Number(q.get('time')), 0), 1);
    if (q.has('exposure') && Number(q.get('exposure')) > 0) P.state.exposure = Number(q.get('exposure'));
    if (q.has('mode')) {
      if (!P.modeAvailable(q.get('mode'))) throw new Error(`this run has no ${q.get('mode')} output`);
      P.state.mode = q.get('mode');
    }
    if (q.get('ui') === '0') document.body.classList.add('bare');
  }

  try {
    P.setupControls();
    applyHash();
    setupMouse(document.getElementById('view'));
    P.syncControls();
    P.render();
    document.body.dataset.rendered = '1';
  } catch (err) {
    document.getElementById('status').textContent = `error: ${err.message}`;
    document.title = `error: ${err.message}`;
    throw err;
  }
})();
