// The rtwall operator console: plain JavaScript over the JSON API (docs/web-console.md). The
// cookie the printed URL set authenticates every request; the event stream brings the status.
'use strict';

const $ = (id) => document.getElementById(id);
let wall = { width: 1, height: 1 };
let lastThumbFrame = -1;
let measuring = false, measurePoints = [];
let cameraEdited = false;
const fpsHistory = [];

function say(text) { $('error').textContent = text || ''; }

async function api(method, path, body) {
  const init = { method, headers: {} };
  if (body !== undefined) {
    init.body = typeof body === 'string' ? body : JSON.stringify(body);
    init.headers['Content-Type'] = typeof body === 'string' ? 'application/toml' : 'application/json';
  }
  const res = await fetch('/api/' + path, init);
  const type = res.headers.get('Content-Type') || '';
  const data = type.includes('json') ? await res.json() : await res.text();
  if (!res.ok) {
    say(`${method} /api/${path}: ${res.status} ${data.error || data}`);
    throw new Error(data.error || res.status);
  }
  say('');
  return data;
}

function numbers(text, count) {
  const v = text.split(',').map((s) => Number(s.trim()));
  if (v.length !== count || v.some((x) => !Number.isFinite(x))) throw new Error(`give ${count} numbers separated by commas`);
  return v;
}

function fmt(v) { return v.map((x) => Number(x.toPrecision(6))).join(', '); }

// ---- status, chart, thumbnail ----
function showStatus(s) {
  wall = s.wall;
  $('status-line').textContent = `frame ${s.frame} · ${s.fps.toFixed(1)} fps · ${s.link_mb_s.toFixed(1)} MB/s · ` +
    `tile latency ${s.tile_latency_ms.toFixed(1)} ms · affinity ${(100 * s.affinity).toFixed(0)} %` +
    (s.tracker ? ' · ' + s.tracker : '') + (s.operating_point ? ' · ' + s.operating_point : '');
  $('frame-label').textContent = `${wall.width}x${wall.height}${wall.stereo ? ' stereo' : ''}, frame ${s.frame}`;
  $('figures').textContent = `${s.tiles_stolen} tiles stolen in the last frame, frame ${s.frame_ms.toFixed(1)} ms`;
  const body = $('clients').querySelector('tbody');
  body.replaceChildren(...s.clients.map((c) => {
    const tr = document.createElement('tr');
    for (const v of [c.id, c.tiles, (100 * c.busy).toFixed(0) + ' %', c.megabytes.toFixed(2)]) {
      const td = document.createElement('td'); td.textContent = v; tr.appendChild(td);
    }
    return tr;
  }));
  fpsHistory.push(s.fps);
  if (fpsHistory.length > 120) fpsHistory.shift();
  drawChart();
  // The fields follow the camera until the operator types in one, and not while one has the
  // focus (a click into a field, then a status update, would replace what is about to be typed).
  if (!cameraEdited && !$('camera-form').contains(document.activeElement)) {
    $('camera-position').value = fmt(s.camera.position);
    $('camera-target').value = fmt(s.camera.target);
    $('camera-up').value = fmt(s.camera.up);
  }
  if (s.frame !== lastThumbFrame) refreshThumbnail(s.frame);
}

function drawChart() {
  const c = $('fps-chart'), g = c.getContext('2d');
  g.clearRect(0, 0, c.width, c.height);
  const max = Math.max(1, ...fpsHistory) * 1.1;
  g.strokeStyle = '#4fc3f7';
  g.beginPath();
  fpsHistory.forEach((v, i) => {
    const x = (i / 119) * c.width, y = c.height - (v / max) * c.height;
    i ? g.lineTo(x, y) : g.moveTo(x, y);
  });
  g.stroke();
  g.fillStyle = '#9e9e9e';
  g.fillText(`${max.toFixed(0)} fps`, 4, 12);
}

let thumbLoading = false;
function refreshThumbnail(frame) {
  if (thumbLoading) return;
  thumbLoading = true;
  const img = new Image();
  img.onload = () => { $('thumbnail').src = img.src; $('thumbnail').dataset.frame = frame; lastThumbFrame = frame; thumbLoading = false; };
  img.onerror = () => { thumbLoading = false; };
  img.src = '/api/thumbnail.jpg?f=' + frame;
}

// ---- parts ----
let partList = [];
async function loadParts() {
  const data = await api('GET', 'parts');
  partList = data.parts;
  renderParts();
}
function renderParts() {
  const q = $('part-search').value.trim().toLowerCase();
  const items = partList.filter((p) => !q || p.path.toLowerCase().includes(q)).slice(0, 500).map((p) => {
    const li = document.createElement('li');
    li.dataset.id = p.id;
    li.className = (p.visible ? '' : 'hidden') + (p.highlighted ? ' highlighted' : '');
    const box = document.createElement('input');
    box.type = 'checkbox'; box.checked = p.visible; box.title = 'visible';
    box.onchange = () => setPart(p.id, { visible: box.checked });
    const name = document.createElement('span');
    // The tree by indentation (a part's depth under its roots); its name, its path on hover.
    let depth = 0;
    for (let q = p.parent; q >= 0 && depth < 64; q = partList[q].parent) depth++;
    name.className = 'name'; name.textContent = p.name; name.title = `${p.path}: ${p.instances} instances`;
    name.style.paddingLeft = `${depth}em`;
    const hi = document.createElement('button');
    hi.type = 'button'; hi.textContent = 'highlight'; hi.className = p.highlighted ? 'on' : '';
    hi.onclick = () => setPart(p.id, { highlight: !p.highlighted });
    const iso = document.createElement('button');
    iso.type = 'button'; iso.textContent = 'isolate';
    iso.onclick = () => setPart(p.id, { isolate: true });
    li.append(box, name, hi, iso);
    return li;
  });
  $('parts').replaceChildren(...items);
}
async function setPart(id, body) {
  try { await api('POST', 'parts/' + id, body); } finally { loadParts(); }
}

// ---- sections ----
async function loadSections() {
  const data = await api('GET', 'sections');
  $('sections').replaceChildren(...data.sections.map((s) => {
    const li = document.createElement('li');
    li.dataset.id = s.id;
    const name = document.createElement('span');
    name.className = 'name';
    name.textContent = `#${s.id} n = (${fmt(s.normal)}), d = ${Number(s.offset.toPrecision(6))}${s.enabled ? '' : ' (off)'}`;
    const offset = document.createElement('input');
    offset.type = 'number'; offset.step = 'any'; offset.value = s.offset; offset.size = 6; offset.title = 'offset';
    offset.onchange = () => api('POST', 'sections/' + s.id, { offset: Number(offset.value) }).then(loadSections);
    const flip = document.createElement('button');
    flip.type = 'button'; flip.textContent = 'flip';
    flip.onclick = () => api('POST', 'sections/' + s.id, { flip: true }).then(loadSections);
    const del = document.createElement('button');
    del.type = 'button'; del.textContent = 'remove';
    del.onclick = () => api('DELETE', 'sections/' + s.id).then(loadSections);
    li.append(name, offset, flip, del);
    return li;
  }));
}

// ---- bookmarks, measurements ----
async function loadBookmarks() {
  const data = await api('GET', 'bookmarks');
  $('bookmarks').replaceChildren(...data.bookmarks.map((b) => {
    const li = document.createElement('li');
    const name = document.createElement('span'); name.className = 'name'; name.textContent = b.name;
    const go = document.createElement('button'); go.type = 'button'; go.textContent = 'go';
    go.onclick = () => api('POST', `bookmarks/${b.id}/go`, {});
    const del = document.createElement('button'); del.type = 'button'; del.textContent = 'delete';
    del.onclick = () => api('DELETE', 'bookmarks/' + b.id).then(loadBookmarks);
    li.append(name, go, del);
    return li;
  }));
}
async function loadMeasurements() {
  const data = await api('GET', 'measurements');
  $('measurements').replaceChildren(...data.measurements.map((m) => {
    const li = document.createElement('li');
    const name = document.createElement('span'); name.className = 'name';
    name.textContent = `${Number(m.distance.toPrecision(7))} units: (${fmt(m.a)}) to (${fmt(m.b)})`;
    const del = document.createElement('button'); del.type = 'button'; del.textContent = 'delete';
    del.onclick = () => api('DELETE', 'measurements/' + m.id).then(loadMeasurements);
    li.append(name, del);
    return li;
  }));
}

function refreshAll() { return Promise.all([loadParts(), loadSections(), loadBookmarks(), loadMeasurements()]).catch(() => {}); }

// ---- wiring ----
$('part-search').oninput = renderParts;
$('show-all').onclick = () => api('POST', 'parts', { show_all: true }).then(loadParts);
$('section-form').onsubmit = (e) => {
  e.preventDefault();
  try {
    api('POST', 'sections', { normal: numbers($('section-normal').value, 3), offset: Number($('section-offset').value) }).then(loadSections);
  } catch (err) { say(err.message); }
};
$('bookmark-form').onsubmit = (e) => {
  e.preventDefault();
  api('POST', 'bookmarks', { name: $('bookmark-name').value }).then(loadBookmarks);
};
$('camera-form').oninput = () => { cameraEdited = true; };
$('camera-form').onsubmit = (e) => {
  e.preventDefault();
  cameraEdited = false;
  try {
    api('POST', 'camera', { position: numbers($('camera-position').value, 3), target: numbers($('camera-target').value, 3),
      up: numbers($('camera-up').value, 3), seconds: 0.5 });
  } catch (err) { say(err.message); }
};
$('measure-toggle').onclick = () => {
  measuring = !measuring; measurePoints = [];
  $('measure-toggle').classList.toggle('on', measuring);
  $('marks').replaceChildren();
};
$('thumbnail').onclick = (e) => {
  if (!measuring) return;
  const r = e.target.getBoundingClientRect();
  const eyes = wall.stereo ? 2 : 1;
  // A stereo thumbnail is both eyes side by side: a click in either is that point of the wall.
  const u = ((e.clientX - r.left) / r.width) * eyes % 1, v = (e.clientY - r.top) / r.height;
  measurePoints.push([Math.min(wall.width - 1, u * wall.width), Math.min(wall.height - 1, v * wall.height)]);
  const dot = document.createElement('div');
  dot.className = 'mark'; dot.style.left = `${e.clientX - r.left}px`; dot.style.top = `${e.clientY - r.top}px`;
  $('marks').appendChild(dot);
  if (measurePoints.length === 2) {
    const [a, b] = measurePoints;
    measurePoints = [];
    api('POST', 'measurements', { a, b }).then(loadMeasurements).finally(() => $('marks').replaceChildren());
  }
};
$('session-file').onchange = async () => {
  const f = $('session-file').files[0];
  if (!f) return;
  await api('POST', 'session', await f.text());
  $('session-file').value = '';
  refreshAll();
};

const events = new EventSource('/api/events');
events.addEventListener('status', (e) => showStatus(JSON.parse(e.data)));
events.addEventListener('state', () => refreshAll());  // the keys, the wand or another console changed something
events.onerror = () => { $('status-line').textContent = 'reconnecting…'; };
refreshAll();
setInterval(refreshAll, 15000);  // besides the 'state' events: after a reconnect, say
