// Penumbra's comparison viewer, embedded in every batch report and in the coordinator's batch and
// job pages (core/report/comparison_viewer.h writes the data it reads and says how the pixels are
// encoded). Without a reference (a farm job without one: data.reference is null) it shows the
// methods alone: no flip, split, error or difference view, and each image's variance relative
// to its own values.
//
// It reads the JSON in #viewer-data, decodes each image (RGBE planes, zlib, decoded by the
// browser's DecompressionStream) and draws the one shown on a canvas: the method chosen by key or
// click, or the reference ("flip"), tonemapped at the chosen exposure, as an error view or as its
// per-pixel variance (the EXR's variance layer, when the image has one). Zoom is
// nearest neighbour down to single pixels, the view is shared by the main canvas and one crop per
// image (synchronized crops), and hovering probes every image's value at the pixel.
//
// The root element's data-* attributes mirror the state (shown, view, zoom, cx, cy, stops) so
// that a test in a real browser can read back what is on screen.
(function () {
  'use strict';
  var root = document.getElementById('viewer');
  var dataElement = document.getElementById('viewer-data');
  if (!root || !dataElement) return;
  var data = JSON.parse(dataElement.textContent);
  var W = data.width, H = data.height, N = W * H;
  var reference = data.reference;
  var hasReference = reference !== null && reference !== undefined;
  var methods = data.methods;
  // Every image: the reference first (when there is one), then the methods (key k shows
  // methods[k - 1], images[k - 1 + base]).
  var base = hasReference ? 1 : 0;
  var images = hasReference ? [reference].concat(methods) : methods.slice();
  function isReference(index) { return hasReference && index === 0; }
  var regions = [{name: 'image', rect: [0, 0, W, H]}].concat(data.regions);
  var regionColours = ['#ff8c00', '#00ccff', '#ff33cc', '#ffff33', '#4dff4d', '#ff4d4d'];
  var MAIN_W = 768, MAIN_H = Math.max(240, Math.min(640, Math.round(MAIN_W * H / W)));
  var CROP_W = 176, CROP_H = Math.round(CROP_W * MAIN_H / MAIN_W);
  var dpr = window.devicePixelRatio || 1;

  var state = {
    method: methods.length ? 0 : -1,  // index into methods
    showReference: hasReference && methods.length === 0,
    view: 'image',  // 'image', 'error' (relative error), 'difference' (signed), 'variance'
    stops: 0,       // exposure relative to data.exposure, in stops
    zoom: 1, cx: W / 2, cy: H / 2,
    split: false, splitAt: 0.5,
    outlines: true, region: 'image',
    probe: null  // [x, y] image pixel under the pointer
  };

  // ---- numbers ----
  function fmt(value) {
    if (value === undefined || value === null || !isFinite(value)) return '–';
    var a = Math.abs(value);
    if (a !== 0 && (a < 1e-3 || a >= 1e5)) return value.toExponential(3);
    return String(Number(value.toPrecision(4)));
  }
  function intervalText(interval) {
    if (!interval) return '–';
    var text = fmt(interval.mean);
    if (interval.lower !== undefined) text += ' [' + fmt(interval.lower) + ', ' + fmt(interval.upper) + ']';
    return text;
  }
  function srgb(linear) {
    if (!(linear > 0)) return 0;
    if (linear >= 1) return 1;
    return linear <= 0.0031308 ? 12.92 * linear : 1.055 * Math.pow(linear, 1 / 2.4) - 0.055;
  }
  // viridis at 9 samples, linear interpolation (as core/report/batch_figure.cpp's).
  var VIRIDIS = [0x440154, 0x472d7b, 0x3b528b, 0x2c728e, 0x21918c, 0x28ae80, 0x5ec962, 0xaddc30, 0xfde725];
  function viridis(t, out, o) {
    if (!isFinite(t)) t = t > 0 ? 1 : 0;
    var p = Math.min(1, Math.max(0, t)) * 8, i = Math.min(7, Math.floor(p)), f = p - i;
    var a = VIRIDIS[i], b = VIRIDIS[i + 1];
    for (var c = 0, shift = 16; c < 3; ++c, shift -= 8)
      out[o + c] = Math.round((((a >> shift) & 255) * (1 - f) + ((b >> shift) & 255) * f));
  }
  // Signed difference: blue below zero, white at zero, red above (ColorBrewer RdBu's ends).
  function diverging(t, out, o) {
    t = Math.max(-1, Math.min(1, isFinite(t) ? t : 0));
    var end = t < 0 ? [33, 102, 172] : [178, 24, 43], w = [247, 247, 247], f = Math.abs(t);
    for (var c = 0; c < 3; ++c) out[o + c] = Math.round(w[c] * (1 - f) + end[c] * f);
  }

  // ---- decoding ----
  var SCALE = new Float64Array(256);  // 2^(stored - 128 - 8), 0 for the black marker
  for (var e = 1; e < 256; ++e) SCALE[e] = Math.pow(2, e - 136);
  // The planes of base64 text, and the linear RGB they hold.
  function decodePlanes(base64, what) {
    var text = atob(base64), bytes = new Uint8Array(text.length);
    for (var i = 0; i < text.length; ++i) bytes[i] = text.charCodeAt(i);
    var stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream('deflate'));
    return new Response(stream).arrayBuffer().then(function (buffer) {
      var planes = new Uint8Array(buffer);
      if (planes.length !== 4 * N) throw new Error(what + ': ' + planes.length + ' bytes, expected ' + 4 * N);
      var rgb = new Float32Array(3 * N);
      for (var p = 0; p < N; ++p) {
        var s = SCALE[planes[3 * N + p]];
        if (s === 0) continue;
        rgb[3 * p] = planes[p] * s;
        rgb[3 * p + 1] = planes[N + p] * s;
        rgb[3 * p + 2] = planes[2 * N + p] * s;
      }
      return {planes: planes, rgb: rgb};
    });
  }
  function decode(image) {
    var pending = [decodePlanes(image.data, image.label).then(function (decoded) {
      image.planes = decoded.planes;
      image.rgb = decoded.rgb;
      delete image.data;
    })];
    if (image.variance) {
      pending.push(decodePlanes(image.variance, image.label + ' variance').then(function (decoded) {
        image.varianceRgb = decoded.rgb;
        delete image.variance;
      }));
    }
    return Promise.all(pending);
  }
  // A pixel's relative variance: mean over channels of variance / (ref^2 + epsilon), its expected
  // term of the MRSE from noise alone.
  function relativeVariance(image, p) {
    var v = image.varianceRgb, r = (hasReference ? reference : image).rgb, sum = 0;
    for (var c = 0; c < 3; ++c) sum += v[3 * p + c] / (r[3 * p + c] * r[3 * p + c] + data.mrse_epsilon);
    return sum / 3;
  }
  // Position of a relative variance on the variance view's logarithmic scale.
  var LOG_LOW = Math.log10(data.variance_scale[0]), LOG_HIGH = Math.log10(data.variance_scale[1]);
  function varianceT(value) {
    return value > 0 ? (Math.log10(value) - LOG_LOW) / (LOG_HIGH - LOG_LOW) : 0;
  }

  // ---- layers: each image in each view, at image resolution ----
  var layers = {};
  var toneLut = null, toneStops = null;
  function toneTable() {
    // Display value of every (exponent, mantissa) pair at the current exposure: exact, and one
    // table lookup per channel instead of a pow.
    if (toneStops === state.stops) return toneLut;
    var k = data.exposure * Math.pow(2, state.stops);
    toneLut = new Uint8ClampedArray(65536);
    for (var e = 1; e < 256; ++e)
      for (var m = 0; m < 256; ++m) toneLut[e * 256 + m] = Math.round(255 * srgb(m * SCALE[e] * k));
    toneStops = state.stops;
    return toneLut;
  }
  function layer(index, view) {
    var key = index + ':' + view + (view === 'image' ? ':' + state.stops : '');
    if (layers[key]) return layers[key];
    var image = images[index], canvas = document.createElement('canvas');
    canvas.width = W; canvas.height = H;
    var context = canvas.getContext('2d'), pixels = context.createImageData(W, H), out = pixels.data;
    var p, o;
    if (view === 'image') {
      var lut = toneTable(), planes = image.planes;
      for (p = 0, o = 0; p < N; ++p, o += 4) {
        var e = planes[3 * N + p] << 8;
        if (e === 0) { out[o] = out[o + 1] = out[o + 2] = 0; } else {
          out[o] = lut[e | planes[p]]; out[o + 1] = lut[e | planes[N + p]]; out[o + 2] = lut[e | planes[2 * N + p]];
        }
        out[o + 3] = 255;
      }
    } else if (view === 'variance') {
      for (p = 0, o = 0; p < N; ++p, o += 4) {
        if (image.varianceRgb) viridis(varianceT(relativeVariance(image, p)), out, o);
        else out[o] = out[o + 1] = out[o + 2] = 85;  // no variance layer: grey
        out[o + 3] = 255;
      }
    } else {
      var x = image.rgb, r = reference.rgb, offset = data.relative_error_offset;
      for (p = 0, o = 0; p < N; ++p, o += 4) {
        var i = 3 * p;
        if (view === 'error') {
          var sum = 0;
          for (var c = 0; c < 3; ++c) sum += Math.abs(x[i + c] - r[i + c]) / (Math.abs(r[i + c]) + offset);
          viridis(sum / 3 / data.error_scale, out, o);
        } else {
          diverging((x[i] - r[i] + x[i + 1] - r[i + 1] + x[i + 2] - r[i + 2]) / 3 / data.difference_scale, out, o);
        }
        out[o + 3] = 255;
      }
    }
    context.putImageData(pixels, 0, 0);
    // Only the current exposure's image layers are kept.
    for (var old in layers) if (old.split(':')[1] === 'image' && old.split(':')[2] !== String(state.stops)) delete layers[old];
    layers[key] = canvas;
    return canvas;
  }

  // ---- DOM ----
  function el(tag, attributes, text) {
    var node = document.createElement(tag);
    for (var name in attributes || {}) node.setAttribute(name, attributes[name]);
    if (text !== undefined) node.textContent = text;
    return node;
  }
  root.appendChild(el('h2', {}, 'Viewer'));
  var status = root.appendChild(el('p', {'class': 'note pv-status'}, 'Decoding the images…'));
  var bar = root.appendChild(el('div', {'class': 'pv-bar'}));
  var methodButtons = bar.appendChild(el('div', {'class': 'pv-group'}));
  var buttons = [];
  images.forEach(function (image, index) {
    var key = isReference(index) ? 'R' : index - base < 9 ? String(index - base + 1) : '';
    var button = el('button', {type: 'button', 'data-index': index, title: image.method + ', ' + image.spp + ' spp'});
    button.appendChild(el('kbd', {}, key));
    button.appendChild(document.createTextNode(' ' + image.label));
    button.addEventListener('click', function () { show(index); });
    methodButtons.appendChild(button);
    buttons.push(button);
  });
  var viewGroup = bar.appendChild(el('div', {'class': 'pv-group'}));
  var viewButtons = {};
  [['image', 'I', 'image'], ['error', 'E', 'relative error'], ['difference', 'D', 'difference'],
   ['variance', 'V', 'variance']].forEach(function (v) {
    if (!hasReference && (v[0] === 'error' || v[0] === 'difference')) return;
    var button = el('button', {type: 'button', 'data-view': v[0]});
    button.appendChild(el('kbd', {}, v[1]));
    button.appendChild(document.createTextNode(' ' + v[2]));
    button.addEventListener('click', function () { setView(v[0]); });
    viewGroup.appendChild(button);
    viewButtons[v[0]] = button;
  });
  var toggles = bar.appendChild(el('div', {'class': 'pv-group'}));
  function toggle(key, text, action) {
    var button = el('button', {type: 'button'});
    button.appendChild(el('kbd', {}, key));
    button.appendChild(document.createTextNode(' ' + text));
    button.addEventListener('click', action);
    return toggles.appendChild(button);
  }
  var splitButton = toggle('S', 'split', function () { state.split = hasReference && !state.split; update(); });
  if (!hasReference) splitButton.style.display = 'none';
  var outlineButton = toggle('O', 'regions', function () { state.outlines = !state.outlines; update(); });
  toggle('F', 'fit', function () { fit(); update(); });
  var exposureLabel = bar.appendChild(el('label', {'class': 'pv-exposure'}, 'exposure '));
  var slider = exposureLabel.appendChild(el('input', {type: 'range', min: '-10', max: '10', step: '0.25', value: '0'}));
  var stopsText = exposureLabel.appendChild(el('span', {}, ''));
  slider.addEventListener('input', function () { state.stops = Number(slider.value); update(); });
  var zoomText = bar.appendChild(el('span', {'class': 'pv-zoom'}, ''));

  var main = root.appendChild(el('div', {'class': 'pv-main'}));
  var wrap = main.appendChild(el('div', {'class': 'pv-wrap'}));
  var canvas = wrap.appendChild(el('canvas', {'class': 'pv-canvas'}));
  canvas.style.width = MAIN_W + 'px'; canvas.style.height = MAIN_H + 'px';
  canvas.width = Math.round(MAIN_W * dpr); canvas.height = Math.round(MAIN_H * dpr);
  var scaleBar = wrap.appendChild(el('div', {'class': 'pv-scale'}));
  var side = main.appendChild(el('div', {'class': 'pv-side'}));
  var title = side.appendChild(el('div', {'class': 'pv-title'}));
  var mrseTable = side.appendChild(el('table', {'class': 'pv-mrse'}));
  var regionList = side.appendChild(el('div', {'class': 'pv-regions'}));
  regions.forEach(function (region, index) {
    var button = el('button', {type: 'button', 'data-region': region.name}, region.name);
    if (index > 0) button.style.borderColor = regionColours[(index - 1) % regionColours.length];
    button.addEventListener('click', function () { selectRegion(region.name); update(); });
    regionList.appendChild(button);
  });
  var probeTable = side.appendChild(el('table', {'class': 'pv-probe'}));

  var crops = root.appendChild(el('div', {'class': 'pv-crops'}));
  var cropCanvases = images.map(function (image, index) {
    var figure = crops.appendChild(el('figure', {'data-index': index}));
    var crop = figure.appendChild(el('canvas', {}));
    crop.style.width = CROP_W + 'px'; crop.style.height = CROP_H + 'px';
    crop.width = Math.round(CROP_W * dpr); crop.height = Math.round(CROP_H * dpr);
    figure.appendChild(el('figcaption', {}, ''));
    figure.addEventListener('click', function () { show(index); });
    return crop;
  });
  root.appendChild(el('p', {'class': 'note pv-help'}, hasReference
      ? 'Keys: 1–9 a method, R or 0 the reference, Space flips between the method and the reference, ' +
        'I image, E relative error |x − ref| / (ref + ' + data.relative_error_offset + '), D signed difference, ' +
        'V variance (of the mean, from the EXR\'s variance layer, relative: σ² / (ref² + ' + data.mrse_epsilon + ')), ' +
        '[ and ] exposure ∓½ stop, + and − zoom (or the wheel), arrows pan (or drag), F fit, S split ' +
        '(drag the divider), O region outlines. Hover a pixel for every image\'s value. The crops below ' +
        'show every image at the same view; click one to show it.'
      : 'No reference: no error views. Keys: 1–9 an image, I image, V variance (of the mean, from the ' +
        'EXR\'s variance layer, relative to the image itself: σ² / (x² + ' + data.mrse_epsilon + ')), ' +
        '[ and ] exposure ∓½ stop, + and − zoom (or the wheel), arrows pan (or drag), F fit, ' +
        'O region outlines. Hover a pixel for its value.'));

  // ---- state changes ----
  function shownIndex() { return (hasReference && state.showReference) || state.method < 0 ? 0 : state.method + base; }
  function show(index) {
    if (isReference(index)) { state.showReference = true; } else { state.method = index - base; state.showReference = false; }
    update();
  }
  function setView(view) { state.view = view; update(); }
  function fit() {
    state.zoom = Math.min(MAIN_W / W, MAIN_H / H);
    state.cx = W / 2; state.cy = H / 2;
  }
  function clampView() {
    state.zoom = Math.min(64, Math.max(Math.min(MAIN_W / W, MAIN_H / H) / 4, state.zoom));
    state.cx = Math.min(W, Math.max(0, state.cx));
    state.cy = Math.min(H, Math.max(0, state.cy));
  }
  function zoomBy(factor, sx, sy) {
    // Keeps the image point under the screen point (sx, sy) (CSS pixels in the canvas) fixed.
    if (sx === undefined) { sx = MAIN_W / 2; sy = MAIN_H / 2; }
    var ix = state.cx + (sx - MAIN_W / 2) / state.zoom, iy = state.cy + (sy - MAIN_H / 2) / state.zoom;
    state.zoom *= factor;
    clampView();
    state.cx = ix - (sx - MAIN_W / 2) / state.zoom;
    state.cy = iy - (sy - MAIN_H / 2) / state.zoom;
    clampView();
  }
  function selectRegion(name) {
    state.region = name;
    var region = regions.filter(function (r) { return r.name === name; })[0];
    if (!region) return;
    var r = region.rect, w = Math.max(1, r[2] - r[0]), h = Math.max(1, r[3] - r[1]);
    state.zoom = name === 'image' ? Math.min(MAIN_W / W, MAIN_H / H) : 0.9 * Math.min(MAIN_W / w, MAIN_H / h);
    state.cx = (r[0] + r[2]) / 2; state.cy = (r[1] + r[3]) / 2;
    clampView();
  }

  // ---- drawing ----
  function drawView(context, width, height, scale, index) {
    // Draws image `index` at the shared view into a canvas of width x height device pixels whose
    // CSS size is `scale` times the main canvas's.
    var z = state.zoom * scale * dpr;
    context.setTransform(1, 0, 0, 1, 0, 0);
    context.imageSmoothingEnabled = false;
    context.setTransform(z, 0, 0, z, width / 2 - state.cx * z, height / 2 - state.cy * z);
    context.drawImage(layer(index, state.view), 0, 0);
  }
  function drawOutlines(context, width, height, scale) {
    if (!state.outlines) return;
    var z = state.zoom * scale * dpr;
    context.setTransform(1, 0, 0, 1, 0, 0);
    context.font = Math.round(12 * dpr) + 'px sans-serif';
    regions.forEach(function (region, index) {
      if (index === 0) return;
      var r = region.rect;
      var x0 = width / 2 + (r[0] - state.cx) * z, y0 = height / 2 + (r[1] - state.cy) * z;
      var x1 = width / 2 + (r[2] - state.cx) * z, y1 = height / 2 + (r[3] - state.cy) * z;
      context.strokeStyle = regionColours[(index - 1) % regionColours.length];
      context.lineWidth = (region.name === state.region ? 3 : 1.5) * dpr;
      context.strokeRect(x0, y0, x1 - x0, y1 - y0);
      if (scale === 1) {
        context.fillStyle = context.strokeStyle;
        context.fillText(region.name, x0 + 3 * dpr, y0 - 4 * dpr);
      }
    });
  }
  function draw() {
    var context = canvas.getContext('2d'), width = canvas.width, height = canvas.height;
    context.setTransform(1, 0, 0, 1, 0, 0);
    context.fillStyle = '#333';
    context.fillRect(0, 0, width, height);
    var index = shownIndex();
    if (state.split && hasReference && index !== 0) {
      var at = Math.round(state.splitAt * width);
      context.save(); context.beginPath(); context.rect(0, 0, at, height); context.clip();
      drawView(context, width, height, 1, index); context.restore();
      context.save(); context.setTransform(1, 0, 0, 1, 0, 0); context.beginPath();
      context.rect(at, 0, width - at, height); context.clip();
      drawView(context, width, height, 1, 0); context.restore();
      context.setTransform(1, 0, 0, 1, 0, 0);
      context.fillStyle = '#fff';
      context.fillRect(at - dpr, 0, 2 * dpr, height);
      context.font = Math.round(13 * dpr) + 'px sans-serif';
      context.fillText(images[index].label, 8 * dpr, height - 10 * dpr);
      context.fillText('reference', at + 8 * dpr, height - 10 * dpr);
    } else {
      drawView(context, width, height, 1, index);
    }
    drawOutlines(context, width, height, 1);
    cropCanvases.forEach(function (crop, i) {
      var c = crop.getContext('2d');
      c.setTransform(1, 0, 0, 1, 0, 0);
      c.fillStyle = '#333';
      c.fillRect(0, 0, crop.width, crop.height);
      drawView(c, crop.width, crop.height, CROP_W / MAIN_W, i);
      drawOutlines(c, crop.width, crop.height, CROP_W / MAIN_W);
    });
  }

  function mrseRows(image) {
    mrseTable.textContent = '';
    var head = mrseTable.appendChild(el('tr'));
    ['region', 'this image', 'corrected, 95% [repeats]'].forEach(function (t) { head.appendChild(el('th', {}, t)); });
    regions.forEach(function (region) {
      var row = mrseTable.appendChild(el('tr', {'data-region': region.name}));
      if (region.name === state.region) row.className = 'pv-selected';
      row.appendChild(el('td', {'class': 'text'}, region.name));
      row.appendChild(el('td', {}, image === reference ? '–' : fmt(image.mrse[region.name])));
      var corrected = image.corrected[region.name];
      row.appendChild(el('td', {}, corrected ? intervalText(corrected) + ' (' + image.repeats + ')' : '–'));
      row.addEventListener('click', function () { selectRegion(region.name); update(); });
    });
  }
  function probeRows() {
    probeTable.textContent = '';
    if (!state.probe) { probeTable.appendChild(el('tr')).appendChild(el('td', {'class': 'text'}, 'Hover the image to probe a pixel.')); return; }
    var x = state.probe[0], y = state.probe[1], i = 3 * (y * W + x), r = hasReference ? reference.rgb : null;
    var offset = data.relative_error_offset;
    var head = probeTable.appendChild(el('tr'));
    ['pixel ' + x + ', ' + y, 'R', 'G', 'B', 'rel. error', 'rel. variance'].forEach(function (t) { head.appendChild(el('th', {}, t)); });
    images.forEach(function (image, index) {
      var row = probeTable.appendChild(el('tr', {'data-index': index}));
      if (index === shownIndex()) row.className = 'pv-selected';
      row.appendChild(el('td', {'class': 'text'}, image.label));
      var sum = 0;
      for (var c = 0; c < 3; ++c) {
        row.appendChild(el('td', {}, fmt(image.rgb[i + c])));
        if (r) sum += Math.abs(image.rgb[i + c] - r[i + c]) / (Math.abs(r[i + c]) + offset);
      }
      row.appendChild(el('td', {}, !r || index === 0 ? '–' : fmt(sum / 3)));
      row.appendChild(el('td', {}, image.varianceRgb ? fmt(relativeVariance(image, y * W + x)) : '–'));
    });
  }
  function scaleLegend() {
    scaleBar.textContent = '';
    if (state.view === 'image') return;
    if (state.view === 'variance') {
      if (!images[shownIndex()].varianceRgb) {
        scaleBar.appendChild(el('span', {'class': 'note'}, 'This image has no variance layer.'));
        return;
      }
      scaleBar.appendChild(el('span', {}, '≤ ' + fmt(data.variance_scale[0])));
      var band = scaleBar.appendChild(el('span', {'class': 'pv-gradient'}));
      band.style.background = 'linear-gradient(to right, #440154, #3b528b, #21918c, #5ec962, #fde725)';
      scaleBar.appendChild(el('span', {}, '≥ ' + fmt(data.variance_scale[1])));
      scaleBar.appendChild(el('span', {'class': 'note'}, hasReference
          ? ' variance of the mean / (ref² + ' + data.mrse_epsilon + '), mean over channels, log scale: ' +
            'the pixel\'s expected MRSE term from noise'
          : ' variance of the mean / (x² + ' + data.mrse_epsilon + '), x the image itself, mean over ' +
            'channels, log scale'));
      return;
    }
    var gradient = state.view === 'error'
        ? 'linear-gradient(to right, #440154, #3b528b, #21918c, #5ec962, #fde725)'
        : 'linear-gradient(to right, rgb(33,102,172), rgb(247,247,247), rgb(178,24,43))';
    scaleBar.appendChild(el('span', {}, state.view === 'error' ? '0' : '−' + fmt(data.difference_scale)));
    var strip = scaleBar.appendChild(el('span', {'class': 'pv-gradient'}));
    strip.style.background = gradient;
    scaleBar.appendChild(el('span', {}, state.view === 'error' ? fmt(data.error_scale) : '+' + fmt(data.difference_scale)));
    scaleBar.appendChild(el('span', {'class': 'note'}, state.view === 'error'
        ? ' relative error, mean over channels' : ' x − ref, mean over channels'));
  }
  function update() {
    var index = shownIndex(), image = images[index];
    buttons.forEach(function (b, i) { b.classList.toggle('pv-on', i === index); });
    for (var v in viewButtons) viewButtons[v].classList.toggle('pv-on', v === state.view);
    splitButton.classList.toggle('pv-on', state.split);
    outlineButton.classList.toggle('pv-on', state.outlines);
    Array.prototype.forEach.call(regionList.children, function (b) { b.classList.toggle('pv-on', b.getAttribute('data-region') === state.region); });
    slider.value = String(state.stops);
    stopsText.textContent = (state.stops >= 0 ? '+' : '−') + Math.abs(state.stops).toFixed(2) + ' EV';
    zoomText.textContent = 'zoom ' + fmt(state.zoom) + '×';
    title.textContent = '';
    title.appendChild(el('b', {}, image.label));
    title.appendChild(document.createTextNode(' ' + image.method + ', ' + image.sampler + ', ' + image.spp + ' spp' +
        (isReference(index) ? ' (reference)' : ', repeat ' + image.repeat + ', ' + fmt(image.compute_seconds) + ' s')));
    mrseRows(image);
    probeRows();
    scaleLegend();
    crops.querySelectorAll('figure').forEach(function (figure, i) {
      figure.classList.toggle('pv-on', i === index);
      var im = images[i], caption = figure.querySelector('figcaption'), corrected = im.corrected[state.region];
      caption.textContent = im.label + (isReference(i) || !hasReference ? '' : ': MRSE ' + state.region + ' ' +
          (corrected ? intervalText(corrected) : fmt(im.mrse[state.region])));
    });
    draw();
    root.setAttribute('data-shown', image.label);
    root.setAttribute('data-shown-index', String(index));
    root.setAttribute('data-view', state.view);
    root.setAttribute('data-zoom', String(state.zoom));
    root.setAttribute('data-cx', String(state.cx));
    root.setAttribute('data-cy', String(state.cy));
    root.setAttribute('data-stops', String(state.stops));
    root.setAttribute('data-split', state.split ? '1' : '0');
    root.setAttribute('data-region', state.region);
  }

  // ---- input ----
  var KEYS = {
    ' ': function () { if (hasReference && state.method >= 0) state.showReference = !state.showReference; },
    r: function () { state.showReference = hasReference; }, '0': function () { state.showReference = hasReference; },
    i: function () { state.view = 'image'; }, e: function () { if (hasReference) state.view = 'error'; },
    d: function () { if (hasReference) state.view = 'difference'; }, v: function () { state.view = 'variance'; },
    '[': function () { state.stops = Math.max(-10, state.stops - 0.5); },
    ']': function () { state.stops = Math.min(10, state.stops + 0.5); },
    '+': function () { zoomBy(2); }, '=': function () { zoomBy(2); }, '-': function () { zoomBy(0.5); },
    f: fit, s: function () { state.split = hasReference && !state.split; }, o: function () { state.outlines = !state.outlines; },
    ArrowLeft: function () { state.cx -= MAIN_W / 8 / state.zoom; clampView(); },
    ArrowRight: function () { state.cx += MAIN_W / 8 / state.zoom; clampView(); },
    ArrowUp: function () { state.cy -= MAIN_H / 8 / state.zoom; clampView(); },
    ArrowDown: function () { state.cy += MAIN_H / 8 / state.zoom; clampView(); }
  };
  document.addEventListener('keydown', function (event) {
    if (!root.hasAttribute('data-ready') || event.ctrlKey || event.metaKey || event.altKey) return;
    var target = event.target, tag = target && target.tagName;
    if (tag === 'TEXTAREA' || (tag === 'INPUT' && target.type !== 'range')) return;
    var key = event.key.length === 1 ? event.key.toLowerCase() : event.key;
    if (/^[1-9]$/.test(key)) {
      if (Number(key) > methods.length) return;
      state.method = Number(key) - 1;
      state.showReference = false;
    } else if (KEYS[key]) {
      KEYS[key]();
    } else {
      return;
    }
    event.preventDefault();
    update();
  });
  function canvasPoint(event) {
    var box = canvas.getBoundingClientRect();
    return [event.clientX - box.left, event.clientY - box.top];
  }
  var drag = null;
  canvas.addEventListener('mousedown', function (event) {
    var p = canvasPoint(event);
    var onDivider = state.split && Math.abs(p[0] - state.splitAt * MAIN_W) < 8;
    drag = {x: p[0], y: p[1], divider: onDivider};
    event.preventDefault();
  });
  window.addEventListener('mouseup', function () { drag = null; });
  canvas.addEventListener('mousemove', function (event) {
    var p = canvasPoint(event);
    if (drag) {
      if (drag.divider) state.splitAt = Math.min(0.98, Math.max(0.02, p[0] / MAIN_W));
      else { state.cx -= (p[0] - drag.x) / state.zoom; state.cy -= (p[1] - drag.y) / state.zoom; clampView(); }
      drag.x = p[0]; drag.y = p[1];
    }
    var x = Math.floor(state.cx + (p[0] - MAIN_W / 2) / state.zoom), y = Math.floor(state.cy + (p[1] - MAIN_H / 2) / state.zoom);
    state.probe = x >= 0 && y >= 0 && x < W && y < H ? [x, y] : null;
    canvas.style.cursor = state.split && Math.abs(p[0] - state.splitAt * MAIN_W) < 8 ? 'ew-resize' : 'crosshair';
    update();
  });
  canvas.addEventListener('mouseleave', function () { state.probe = null; update(); });
  canvas.addEventListener('wheel', function (event) {
    var p = canvasPoint(event);
    zoomBy(Math.pow(2, -event.deltaY / 240), p[0], p[1]);
    event.preventDefault();
    update();
  }, {passive: false});

  // Cells of the batch table (data-viewer-label, data-viewer-region) show their method and region.
  document.querySelectorAll('[data-viewer-label]').forEach(function (cell) {
    cell.classList.add('pv-link');
    cell.addEventListener('click', function () {
      var label = cell.getAttribute('data-viewer-label');
      for (var m = 0; m < methods.length; ++m)
        if (methods[m].label === label) { state.method = m; state.showReference = false; }
      var region = cell.getAttribute('data-viewer-region');
      if (region) selectRegion(region);
      update();
      root.scrollIntoView({behavior: 'smooth', block: 'start'});
    });
  });

  // ---- start ----
  if (typeof DecompressionStream === 'undefined') {
    status.textContent = 'This browser cannot decompress the images (no DecompressionStream); the figure below shows them.';
    root.setAttribute('data-error', 'no DecompressionStream');
    return;
  }
  Promise.all(images.map(decode)).then(function () {
    status.textContent = W + '×' + H + ' pixels, ' + methods.length + ' method(s)' +
        (hasReference ? ' and the reference' : ', no reference') + '; the values are ' +
        'the EXRs\' to within 0.4% of each pixel\'s brightest channel.';
    fit();
    root.setAttribute('data-ready', '1');
    update();
  }).catch(function (error) {
    status.textContent = 'The viewer could not decode its images: ' + error.message;
    root.setAttribute('data-error', error.message);
  });
})();
