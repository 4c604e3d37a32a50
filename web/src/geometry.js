// Camera-frame geometry for drawing: pinhole projection and box wireframes.
// Camera frame x right, y down, z forward, metres (as the API).

// Pixel (u, v) of a camera-frame point, or null behind the camera.
export function project(k, p) {
  if (!(p[2] > 1e-6)) return null;
  return [k.fx * (p[0] / p[2]) + k.cx, k.fy * (p[1] / p[2]) + k.cy];
}

// A point through a row-major 4x4 transform.
export function transform(t, p) {
  return [0, 1, 2].map((r) => t[r][0] * p[0] + t[r][1] * p[1] + t[r][2] * p[2] + t[r][3]);
}

// The 8 corners of an l x b x h box (origin at the centroid) in the camera frame.
export function boxCorners(cameraTbox, dims) {
  const [l, b, h] = dims.map((d) => d / 2);
  const corners = [];
  for (const sx of [-1, 1]) for (const sy of [-1, 1]) for (const sz of [-1, 1]) {
    corners.push(transform(cameraTbox, [sx * l, sy * b, sz * h]));
  }
  return corners;
}

// Index pairs into boxCorners' order: the 12 edges of a box.
export const BOX_EDGES = [
  [0, 1], [2, 3], [4, 5], [6, 7], // along z
  [0, 2], [1, 3], [4, 6], [5, 7], // along y
  [0, 4], [1, 5], [2, 6], [3, 7], // along x
];

// Edge points arrive as a flat [x0, y0, z0, x1, ...] list.
export function* triples(flat) {
  for (let i = 0; i + 2 < flat.length; i += 3) yield [flat[i], flat[i + 1], flat[i + 2]];
}
