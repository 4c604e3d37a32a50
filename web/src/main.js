// The web view: / lists the sources; /sources/NAME shows one live (2D and 3D views).
import './style.css';
import { getJSON, paths, subscribe } from './api.js';
import { CloudView } from './cloud_view.js';
import { startCellView } from './cell_view.js';
import { cell, fixed, hz, ms, row, seconds, vec } from './format.js';
import { ImageView } from './image_view.js';

const $ = (id) => document.getElementById(id);
const params = new URLSearchParams(location.search);
const route = decodeURIComponent(location.pathname).match(/^\/sources\/([^/]+)\/?$/);

async function loadSources() {
  const { sources } = await getJSON(paths.sources());
  const tabs = $('source-tabs');
  tabs.replaceChildren(...sources.map((s) => {
    const a = document.createElement('a');
    a.href = `/sources/${encodeURIComponent(s.name)}`;
    a.textContent = s.name;
    if (route && route[1] === s.name) a.className = 'active';
    return a;
  }));
  return sources;
}

function setConnection(ok, text) {
  const pill = $('connection');
  pill.textContent = text;
  pill.className = `pill ${ok ? 'ok' : 'bad'}`;
}

async function overview() {
  $('overview').hidden = false;
  const refresh = async () => {
    try {
      const sources = await loadSources();
      setConnection(true, 'live');
      $('source-table').tBodies[0].replaceChildren(...sources.map((s) => {
        const link = document.createElement('a');
        link.href = `/sources/${encodeURIComponent(s.name)}`;
        link.textContent = s.name;
        const name = document.createElement('td');
        name.appendChild(link);
        return row([name, cell(s.state + (s.state_reason ? `: ${s.state_reason}` : ''), `state-${s.state}`),
          cell(hz(s.fps)), cell(seconds(s.frame_age_s)), cell(ms(s.detection_ms)), cell(s.box_model || '–'),
          cell(s.description)]);
      }));
    } catch (e) {
      setConnection(false, 'server unreachable');
    }
  };
  await refresh();
  setInterval(refresh, 2000);
  startCellView($('cell-overview'));
}

async function sourcePage(name) {
  $('source-page').hidden = false;
  $('source-name').textContent = name;
  document.title = `cornerpose · ${name}`;
  const sources = await loadSources().catch(() => []);
  const source = sources.find((s) => s.name === name);
  showState(source || { state: 'UNKNOWN', state_reason: 'no such source' });
  const box = params.get('box') || source?.box_model || '';

  const image = new ImageView($('image-view'));
  const cloud = new CloudView($('cloud-view'));
  const arrivals = [];
  image.onDrawn = (d) => {
    const count = $('box-count');
    count.textContent = `${d.boxes.length}`;
    count.dataset.frameId = `${d.frame_id}`;
    $('image-caption').textContent = `${d.source} frame ${d.frame_id} (${d.image.kind})`;
    document.body.dataset.frameId = `${d.frame_id}`;
  };
  const onDetection = (d) => {
    const now = performance.now();
    arrivals.push(now);
    while (arrivals.length > 1 && now - arrivals[0] > 5000) arrivals.shift();
    const rate = arrivals.length > 1 ? (arrivals.length - 1) / ((now - arrivals[0]) / 1000) : NaN;
    $('frame-id').textContent = `${d.frame_id}`;
    $('frame-rate').textContent = hz(rate);
    $('frame-age').textContent = seconds(Date.now() / 1000 - d.capture_time_unix_ms / 1000);
    $('detection-time').textContent = ms(d.timings_ms.total);
    $('box-table').tBodies[0].replaceChildren(...d.boxes.map((b, i) => row([
      cell(`${i}`), cell(fixed(b.score, 2)), cell(vec(b.camera_T_box.slice(0, 3).map((r) => r[3]))),
      cell(b.grasp_face), cell(vec(b.grasp_centre)),
    ])));
    image.show(d);
    cloud.show(d);
  };
  const onError = (e) => setConnection(false, e.status === 404 ? 'no such source' : 'no frame yet');
  getJSON(paths.latest(name, box)).then(onDetection).catch(onError);
  subscribe(name, box, {
    open: () => setConnection(true, 'live'),
    error: () => setConnection(false, 'reconnecting'),
    detection: onDetection,
    state: showState,
  });
  startCellView($('cell'));
}

function showState(s) {
  const el = $('source-state');
  el.textContent = s.state + (s.state_reason ? `: ${s.state_reason}` : '');
  el.className = `state-${s.state}`;
}

if (route) sourcePage(route[1]); else overview();
