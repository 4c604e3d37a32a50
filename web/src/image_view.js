// The 2D view: the newest frame (depth shaded, or colour) with the detection drawn over it.
import { BOX_EDGES, boxCorners, project, triples } from './geometry.js';

const css = (name) => getComputedStyle(document.documentElement).getPropertyValue(name).trim();

export class ImageView {
  constructor(canvas) {
    this.canvas = canvas;
    this.ctx = canvas.getContext('2d');
    this.loading = null; // the detection whose image is being fetched
    this.pending = null; // the newest detection that arrived meanwhile
    this.onDrawn = null; // called with each detection once it is on screen
  }

  // Shows a detection: its image is fetched, then the overlay drawn. While an
  // image loads only the newest later detection is kept (no backlog).
  show(detection) {
    if (this.loading) { this.pending = detection; return; }
    this.loading = detection;
    const image = new Image();
    image.onload = () => this.finish(detection, image);
    image.onerror = () => this.finish(detection, null);
    image.src = detection.image.url;
  }

  finish(detection, image) {
    this.draw(detection, image);
    this.loading = null;
    if (this.pending) {
      const next = this.pending;
      this.pending = null;
      this.show(next);
    }
  }

  draw(d, image) {
    const { ctx, canvas } = this;
    const k = d.intrinsics;
    if (canvas.width !== k.width || canvas.height !== k.height) {
      canvas.width = k.width;
      canvas.height = k.height;
    }
    ctx.fillStyle = '#000';
    ctx.fillRect(0, 0, canvas.width, canvas.height);
    if (image) ctx.drawImage(image, 0, 0, canvas.width, canvas.height);

    ctx.fillStyle = css('--edge');
    for (const p of triples(d.edge_points || [])) {
      const uv = project(k, p);
      if (uv) ctx.fillRect(uv[0] - 0.5, uv[1] - 0.5, 1.5, 1.5);
    }
    ctx.lineWidth = 2;
    ctx.strokeStyle = css('--segment');
    for (const s of d.segments) this.line(k, s.end1, s.end2);
    ctx.strokeStyle = css('--box');
    for (const box of d.boxes) {
      const corners = boxCorners(box.camera_T_box, d.box_dims);
      for (const [a, b] of BOX_EDGES) this.line(k, corners[a], corners[b]);
    }
    ctx.fillStyle = css('--corner');
    for (const c of d.corners) this.dot(k, c, 3.5);
    ctx.fillStyle = css('--grasp');
    ctx.strokeStyle = css('--grasp');
    d.boxes.forEach((box, i) => {
      this.dot(k, box.grasp_centre, 5);
      const tip = box.grasp_centre.map((x, j) => x + 0.08 * box.grasp_normal[j]);
      this.line(k, box.grasp_centre, tip);
      const uv = project(k, box.grasp_centre);
      if (uv) {
        ctx.font = 'bold 14px system-ui, sans-serif';
        ctx.fillText(`${i}`, uv[0] + 7, uv[1] - 7);
      }
    });
    this.onDrawn?.(d);
  }

  line(k, a, b) {
    const pa = project(k, a);
    const pb = project(k, b);
    if (!pa || !pb) return;
    this.ctx.beginPath();
    this.ctx.moveTo(pa[0], pa[1]);
    this.ctx.lineTo(pb[0], pb[1]);
    this.ctx.stroke();
  }

  dot(k, p, radius) {
    const uv = project(k, p);
    if (!uv) return;
    this.ctx.beginPath();
    this.ctx.arc(uv[0], uv[1], radius, 0, 2 * Math.PI);
    this.ctx.fill();
  }
}
