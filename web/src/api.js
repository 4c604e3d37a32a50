// The server's JSON HTTP API (web/README.md): fetches and the server-sent event stream.

export async function getJSON(path) {
  const response = await fetch(path, { cache: 'no-store' });
  if (!response.ok) {
    const text = await response.text();
    const error = new Error(`${path}: ${response.status} ${text}`);
    error.status = response.status;
    throw error;
  }
  return response.json();
}

export async function getArrayBuffer(path) {
  const response = await fetch(path, { cache: 'no-store' });
  if (!response.ok) throw new Error(`${path}: ${response.status}`);
  return response.arrayBuffer();
}

const encode = encodeURIComponent;
export const paths = {
  sources: () => '/api/sources',
  latest: (name, box) => `/api/sources/${encode(name)}/latest${boxQuery(box)}`,
  events: (name, box) => `/api/sources/${encode(name)}/events${boxQuery(box)}`,
  cell: () => '/api/cell',
};

function boxQuery(box) { return box ? `?box=${encode(box)}` : ''; }

// Subscribes to a source's detections. handlers: detection(d), state(source),
// open(), error(). EventSource reconnects by itself after a dropped stream.
export function subscribe(name, box, handlers) {
  const events = new EventSource(paths.events(name, box));
  events.addEventListener('detection', (e) => handlers.detection?.(JSON.parse(e.data)));
  events.addEventListener('state', (e) => handlers.state?.(JSON.parse(e.data)));
  events.onopen = () => handlers.open?.();
  events.onerror = () => handlers.error?.();
  return () => events.close();
}

// Decodes the compact cloud (see web/README.md): a little-endian header
// "CPC1", uint32 point count, uint32 flags (bit 0: rgb follows), then float32
// x, y, z per point and, with rgb, uint8 r, g, b per point.
export function decodeCloud(buffer) {
  const view = new DataView(buffer);
  const magic = String.fromCharCode(...new Uint8Array(buffer, 0, 4));
  if (magic !== 'CPC1') throw new Error(`cloud: bad magic ${magic}`);
  const count = view.getUint32(4, true);
  const flags = view.getUint32(8, true);
  const positions = new Float32Array(buffer.slice(12, 12 + count * 12));
  let colors = null;
  if (flags & 1) {
    const rgb = new Uint8Array(buffer, 12 + count * 12, count * 3);
    colors = new Float32Array(count * 3);
    for (let i = 0; i < rgb.length; ++i) colors[i] = rgb[i] / 255;
  }
  return { count, positions, colors };
}
