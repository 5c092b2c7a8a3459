// hdr4d viewer, the page: the dataset's cameras (picker), orbit and zoom with the mouse, the time
// slider and play, the exposure slider, the LDR/HDR switch, and a view chosen by the URL's hash
// (#camera=test:0&time=0.5&exposure=0.25&mode=ldr&ui=0; ui=0 shows the canvas alone, for
// screenshots). Renders once per change; the data comes from the page (viewer_page.cpp).
'use strict';
(function () {
  const M = window.hdr4dViewerMaths, S = window.hdr4dViewerSplats;
  const $ = (id) => document.getElementById(id);
  const data = JSON.parse($('hdr4d-data').textContent);
  const ply = M.parsePly(M.base64Bytes($('hdr4d-ply').textContent));
  const model = M.prepareModel(ply);
  const tone = (() => {
    if (!data.tone) return null;
    const t = Object.assign({}, data.tone);
    t.values = new Float32Array(M.base64Bytes(data.tone.values).buffer);
    return t;
  })();
  const numbers = (key) => (ply.comments[key] || []).map(Number).filter((v) => !Number.isNaN(v));
  const learned = numbers('hdr4d-learned-background');
  const headBackground = numbers('hdr4d-hdr-head-background');
  const grey = numbers('hdr4d-background')[0] || 0;
  const frame = new Float32Array(Math.max(model.n, 1) * S.FLOATS);
  const renderer = window.hdr4dViewerGl.createRenderer($('view'));
  const state = {
    camera: null, time: 0, exposure: data.exposure.median,
    mode: model.logHdr && !tone ? 'hdr' : 'ldr', playing: false,
  };

  function copyCamera(c) {
    return { R: c.R.slice(), t: c.t.slice(), fx: c.fx, fy: c.fy, cx: c.cx, cy: c.cy,
      width: c.width, height: c.height };
  }

  // The background behind every Gaussian in the output shown (learned_background.h).
  function background() {
    if (!model.logHdr) return learned.length === 3 ? learned : [grey, grey, grey];
    if (state.mode === 'hdr') {
      if (learned.length !== 3) return [0, 0, 0];
      const scale = Math.exp(data.hdr_log_scale);
      return learned.map((b, c) => Math.exp(Math.min(b + (headBackground[c] || 0), 30)) * scale);
    }
    if (learned.length !== 3) return [grey, grey, grey];
    const row = M.timeIndex(state.time, data.num_times);
    return learned.map((b, c) => M.toneLookup(tone, toneRowOf(row), Math.log(state.exposure), b, c));
  }

  function toneRowOf(timeIndex) {
    let best = 0;
    tone.time_indices.forEach((ti, r) => {
      if (Math.abs(ti - timeIndex) < Math.abs(tone.time_indices[best] - timeIndex)) best = r;
    });
    return best;
  }

  // LDR needs LDR colours or baked curves; HDR needs log-HDR colours.
  const modeAvailable = (mode) => (mode === 'hdr' ? model.logHdr : !model.logHdr || !!tone);

  function render() {
    const start = performance.now();
    const hdr = model.logHdr && state.mode === 'hdr';
    const view = {
      camera: state.camera, time: state.time, mode: hdr ? 'hdr' : 'ldr', tone,
      toneRow: tone ? toneRowOf(M.timeIndex(state.time, data.num_times)) : 0,
      logExposure: Math.log(state.exposure), hdrScale: Math.exp(data.hdr_log_scale),
    };
    const count = S.buildFrame(model, view, frame);
    renderer.draw(frame, count, state.camera, background(), hdr, state.exposure);
    // Small cameras are shown enlarged (not in the bare view, whose pixels are the camera's).
    const canvas = $('view');
    canvas.style.width = document.body.classList.contains('bare') ? ''
      : `${Math.max(state.camera.width, Math.min(640, 4 * state.camera.width))}px`;
    $('status').textContent = `${count} of ${model.n} Gaussians, ${(performance.now() - start).toFixed(0)} ms`;
    document.title = `${data.title} (t ${state.time.toFixed(3)})`;
  }

  // Sliders and labels follow the state.
  const logMin = Math.log(data.exposure.slider_min), logMax = Math.log(data.exposure.slider_max);
  function syncControls() {
    $('time').value = state.time;
    $('time-value').textContent = state.time.toFixed(3);
    const u = logMax > logMin ? (Math.log(state.exposure) - logMin) / (logMax - logMin) : 0.5;
    $('exposure').value = Math.round(Math.min(Math.max(u, 0), 1) * 1000);
    $('exposure-value').textContent = `${state.exposure.toPrecision(3)} s`;
    for (const r of document.querySelectorAll('input[name=mode]')) r.checked = r.value === state.mode;
  }

  function pickCamera(k) {
    const c = data.cameras[k];
    state.camera = copyCamera(c);
    state.time = c.time;
    state.exposure = c.exposure;
  }

  function setupControls() {
    $('title').textContent = data.title;
    $('method').textContent = `method ${data.method}, ${model.n} Gaussians`;
    $('note').textContent = data.ldr_note;
    data.cameras.forEach((c, k) => {
      const o = document.createElement('option');
      o.value = k;
      o.textContent = `${c.split} ${c.index}: ${c.file} (t ${c.time.toFixed(3)}, ${c.exposure} s)`;
      $('camera').appendChild(o);
    });
    $('camera').onchange = () => { pickCamera(Number($('camera').value)); syncControls(); render(); };
    $('time').oninput = () => { state.time = Number($('time').value); syncControls(); render(); };
    $('exposure').oninput = () => {
      state.exposure = Math.exp(logMin + (logMax - logMin) * Number($('exposure').value) / 1000);
      syncControls(); render();
    };
    for (const r of document.querySelectorAll('input[name=mode]')) {
      r.disabled = !modeAvailable(r.value);
      r.onchange = () => { state.mode = r.value; syncControls(); render(); };
    }
    $('play').onclick = () => {
      state.playing = !state.playing;
      $('play').textContent = state.playing ? 'Pause' : 'Play';
      if (state.playing) requestAnimationFrame(step);
    };
  }

  function step() {
    if (!state.playing) return;
    state.time = (state.time + 1 / Math.max(4 * data.num_times, 60)) % 1;
    syncControls();
    render();
    requestAnimationFrame(step);
  }

  window.hdr4dViewerPage = { modeAvailable, state, render, syncControls, pickCamera, setupControls, data, model };
})();
