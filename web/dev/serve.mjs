// Development only: serves the built page (dist/) against web/dev/fixture.json, with a
// fake event stream, so the front end can be worked on without a server.
//   node build.mjs && node dev/serve.mjs [PORT]
// The real API is served by cornerpose_server (web/README.md); tests use that.
import { createServer } from 'node:http';
import { readFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const dist = join(here, '..', 'dist');
const fixture = JSON.parse(readFileSync(join(here, 'fixture.json'), 'utf8'));
const types = { '.js': 'text/javascript', '.css': 'text/css', '.html': 'text/html' };

// A tilted floor and the fixture's box top as points, in the compact cloud format.
function cloud() {
  const points = [];
  for (let x = -0.5; x <= 0.5; x += 0.01) for (let y = -0.4; y <= 0.4; y += 0.01) {
    const top = Math.abs(x - 0.05) < 0.15 && Math.abs(y - 0.02) < 0.1;
    points.push(x, y, top ? 1.05 : 1.2);
  }
  const buffer = Buffer.alloc(12 + points.length * 4);
  buffer.write('CPC1', 0, 'latin1');
  buffer.writeUInt32LE(points.length / 3, 4);
  buffer.writeUInt32LE(0, 8);
  points.forEach((v, i) => buffer.writeFloatLE(v, 12 + 4 * i));
  return buffer;
}
const svg = '<svg xmlns="http://www.w3.org/2000/svg" width="640" height="480"><defs><linearGradient id="g">' +
  '<stop offset="0" stop-color="#333"/><stop offset="1" stop-color="#999"/></linearGradient></defs>' +
  '<rect width="640" height="480" fill="url(#g)"/><rect x="245" y="150" width="150" height="100" fill="#ddd"/></svg>';

let frame = 1;
const detection = () => ({ ...fixture.detection, frame_id: frame, capture_time_unix_ms: Date.now() });
createServer((req, res) => {
  const url = new URL(req.url, 'http://x');
  const json = (body) => { res.writeHead(200, { 'content-type': 'application/json' }); res.end(JSON.stringify(body)); };
  if (url.pathname === '/api/sources') return json(fixture.sources);
  if (url.pathname === '/api/cell') return json(fixture.cell);
  if (url.pathname.endsWith('/latest')) return json(detection());
  if (url.pathname.endsWith('/events')) {
    res.writeHead(200, { 'content-type': 'text/event-stream', 'cache-control': 'no-cache' });
    const timer = setInterval(() => {
      frame += 1;
      res.write(`event: detection\ndata: ${JSON.stringify(detection())}\n\n`);
    }, 500);
    req.on('close', () => clearInterval(timer));
    return undefined;
  }
  if (url.pathname === '/dev/image.svg') { res.writeHead(200, { 'content-type': 'image/svg+xml' }); return res.end(svg); }
  if (url.pathname === '/dev/cloud.bin') return res.end(cloud());
  const file = url.pathname.startsWith('/assets/') ? url.pathname : '/index.html';
  try {
    const body = readFileSync(join(dist, file));
    res.writeHead(200, { 'content-type': types[file.slice(file.lastIndexOf('.'))] || 'application/octet-stream' });
    return res.end(body);
  } catch {
    res.writeHead(404);
    return res.end('not found');
  }
}).listen(Number(process.argv[2] || 8089), '127.0.0.1', function () {
  console.log(`dev server on http://127.0.0.1:${this.address().port}/`);
});
