// hdr4d viewer, WebGL 2: each splat (splats.js) is projected with the EWA approximation of 3DGS
// (method/gaussian/projection.h: the 1.3 x tan(fov/2) guard band, 0.3 px^2 dilation) and drawn
// as a screen-space quad over the pixels where its alpha can reach 1/255; the fragment computes
// alpha = min(0.99, opacity exp(-d^T conic d / 2)), drops alpha < 1/255, and blends far to near
// into a float image that starts as the background. A second pass shows that image: clamped
// (LDR), or exposure x radiance encoded as sRGB (HDR).
'use strict';
(function () {
  const SPLAT_VS = `#version 300 es
  precision highp float;
  layout(location = 0) in vec3 a_mean;
  layout(location = 1) in vec3 a_cov0;   // xx xy xz
  layout(location = 2) in vec3 a_cov1;   // yy yz zz
  layout(location = 3) in vec4 a_color;  // rgb, opacity x p(t)
  uniform mat3 u_rotation;  // cam_from_world (OpenCV axes)
  uniform vec3 u_translation;
  uniform vec2 u_focal, u_principal, u_size;
  out vec2 v_mean;
  out vec3 v_conic;
  out vec4 v_color;
  void main() {
    gl_Position = vec4(0.0, 0.0, 2.0, 1.0);  // culled unless set below
    vec3 p = u_rotation * a_mean + u_translation;
    if (p.z <= 0.2 || a_color.a < 1.0 / 255.0) return;
    float iz = 1.0 / p.z;
    vec2 lim = 1.3 * u_size / (2.0 * u_focal);
    vec2 j = clamp(p.xy * iz, -lim, lim);
    vec3 j0 = vec3(u_focal.x * iz, 0.0, -u_focal.x * j.x * iz);
    vec3 j1 = vec3(0.0, u_focal.y * iz, -u_focal.y * j.y * iz);
    vec3 m0 = transpose(u_rotation) * j0, m1 = transpose(u_rotation) * j1;
    mat3 sigma = mat3(a_cov0.x, a_cov0.y, a_cov0.z, a_cov0.y, a_cov1.x, a_cov1.y,
                      a_cov0.z, a_cov1.y, a_cov1.z);
    float a = dot(m0, sigma * m0) + 0.3, b = dot(m0, sigma * m1), c = dot(m1, sigma * m1) + 0.3;
    float det = a * c - b * b;
    if (!(det > 0.0)) return;
    v_mean = u_focal * p.xy * iz + u_principal;
    v_conic = vec3(c, -b, a) / det;
    v_color = a_color;
    // alpha >= 1/255 only where d^T conic d <= 2 ln(255 opacity): per axis sqrt(2 ln(.) cov).
    float reach = sqrt(2.0 * log(255.0 * min(a_color.a, 0.99)));
    vec2 extent = reach * sqrt(vec2(a, c)) + 1.0;
    vec2 corner = vec2(float(gl_VertexID & 1), float(gl_VertexID >> 1)) * 2.0 - 1.0;
    vec2 pixel = v_mean + corner * extent;
    gl_Position = vec4(pixel.x / u_size.x * 2.0 - 1.0, 1.0 - pixel.y / u_size.y * 2.0, 0.0, 1.0);
  }`;
  const SPLAT_FS = `#version 300 es
  precision highp float;
  uniform vec2 u_size;
  in vec2 v_mean;
  in vec3 v_conic;
  in vec4 v_color;
  out vec4 color;
  void main() {
    // Pixel centres at (i + 0.5, j + 0.5), v downwards (core/geometry/camera.h).
    vec2 d = vec2(gl_FragCoord.x, u_size.y - gl_FragCoord.y) - v_mean;
    float power = -0.5 * (v_conic.x * d.x * d.x + v_conic.z * d.y * d.y) - v_conic.y * d.x * d.y;
    if (power > 0.0) discard;
    float alpha = min(0.99, v_color.a * exp(power));
    if (alpha < 1.0 / 255.0) discard;
    color = vec4(v_color.rgb * alpha, alpha);
  }`;
  const SHOW_VS = `#version 300 es
  void main() {
    vec2 p = vec2(float(gl_VertexID == 1) * 4.0 - 1.0, float(gl_VertexID == 2) * 4.0 - 1.0);
    gl_Position = vec4(p, 0.0, 1.0);
  }`;
  const SHOW_FS = `#version 300 es
  precision highp float;
  uniform sampler2D u_image;
  uniform int u_hdr;
  uniform float u_exposure;
  out vec4 color;
  void main() {
    vec3 v = texelFetch(u_image, ivec2(gl_FragCoord.xy), 0).rgb;
    if (u_hdr == 1) {
      v = clamp(v * u_exposure, 0.0, 1.0);
      v = mix(v * 12.92, 1.055 * pow(v, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, v));
    }
    color = vec4(clamp(v, 0.0, 1.0), 1.0);
  }`;

  function compile(gl, vs, fs) {
    const program = gl.createProgram();
    for (const [type, text] of [[gl.VERTEX_SHADER, vs], [gl.FRAGMENT_SHADER, fs]]) {
      const s = gl.createShader(type);
      gl.shaderSource(s, text);
      gl.compileShader(s);
      if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
      gl.attachShader(program, s);
    }
    gl.linkProgram(program);
    if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(program));
    return program;
  }

  function createRenderer(canvas) {
    const gl = canvas.getContext('webgl2', { antialias: false, preserveDrawingBuffer: true, alpha: false });
    if (!gl) throw new Error('this browser has no WebGL 2');
    if (!gl.getExtension('EXT_color_buffer_float')) throw new Error('WebGL 2 without float render targets');
    // 32-bit float blending where the browser has it, else half floats (about 3 decimal digits).
    const full = !!gl.getExtension('EXT_float_blend');
    const splat = compile(gl, SPLAT_VS, SPLAT_FS), show = compile(gl, SHOW_VS, SHOW_FS);
    const buffer = gl.createBuffer(), vao = gl.createVertexArray();
    gl.bindVertexArray(vao);
    gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
    const layout = [[0, 3, 0], [1, 3, 3], [2, 3, 6], [3, 4, 9]];
    for (const [loc, size, offset] of layout) {
      gl.enableVertexAttribArray(loc);
      gl.vertexAttribPointer(loc, size, gl.FLOAT, false, 13 * 4, offset * 4);
      gl.vertexAttribDivisor(loc, 1);
    }
    let target = null, size = [0, 0];
    function ensureTarget(w, h) {
      if (target && size[0] === w && size[1] === h) return;
      if (target) { gl.deleteTexture(target.texture); gl.deleteFramebuffer(target.fbo); }
      const texture = gl.createTexture();
      gl.bindTexture(gl.TEXTURE_2D, texture);
      gl.texStorage2D(gl.TEXTURE_2D, 1, full ? gl.RGBA32F : gl.RGBA16F, w, h);
      // Float textures are not filterable without an extension: nearest, or they read as black.
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
      const fbo = gl.createFramebuffer();
      gl.bindFramebuffer(gl.FRAMEBUFFER, fbo);
      gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, texture, 0);
      target = { texture, fbo };
      size = [w, h];
    }
    // frame: Float32Array of `count` splats far to near; cam: {R, t, fx, fy, cx, cy, width,
    // height}; background: rgb; hdr: show exposure x radiance as sRGB.
    function draw(frame, count, cam, background, hdr, exposure) {
      const w = cam.width, h = cam.height;
      if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
      ensureTarget(w, h);
      gl.bindFramebuffer(gl.FRAMEBUFFER, target.fbo);
      gl.viewport(0, 0, w, h);
      gl.clearColor(background[0], background[1], background[2], 1);
      gl.clear(gl.COLOR_BUFFER_BIT);
      gl.useProgram(splat);
      const R = cam.R;  // row-major; GLSL takes columns
      gl.uniformMatrix3fv(gl.getUniformLocation(splat, 'u_rotation'), false,
        [R[0], R[3], R[6], R[1], R[4], R[7], R[2], R[5], R[8]]);
      gl.uniform3fv(gl.getUniformLocation(splat, 'u_translation'), cam.t);
      gl.uniform2f(gl.getUniformLocation(splat, 'u_focal'), cam.fx, cam.fy);
      gl.uniform2f(gl.getUniformLocation(splat, 'u_principal'), cam.cx, cam.cy);
      gl.uniform2f(gl.getUniformLocation(splat, 'u_size'), w, h);
      gl.enable(gl.BLEND);
      gl.blendFunc(gl.ONE, gl.ONE_MINUS_SRC_ALPHA);
      gl.bindVertexArray(vao);
      gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
      gl.bufferData(gl.ARRAY_BUFFER, frame.subarray(0, count * 13), gl.DYNAMIC_DRAW);
      gl.drawArraysInstanced(gl.TRIANGLE_STRIP, 0, 4, count);
      gl.disable(gl.BLEND);
      gl.bindFramebuffer(gl.FRAMEBUFFER, null);
      gl.useProgram(show);
      gl.activeTexture(gl.TEXTURE0);
      gl.bindTexture(gl.TEXTURE_2D, target.texture);
      gl.uniform1i(gl.getUniformLocation(show, 'u_image'), 0);
      gl.uniform1i(gl.getUniformLocation(show, 'u_hdr'), hdr ? 1 : 0);
      gl.uniform1f(gl.getUniformLocation(show, 'u_exposure'), exposure);
      gl.drawArrays(gl.TRIANGLES, 0, 3);
      gl.finish();
    }
    return { draw, fullFloat: full };
  }

  window.hdr4dViewerGl = { createRenderer };
})();
