// The 3D view: the frame's cloud as points and the boxes as wireframes; the mouse turns it.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { BOX_EDGES, boxCorners, triples } from './geometry.js';
import { decodeCloud, getArrayBuffer } from './api.js';

const COLORS = { edge: 0xff4040, segment: 0x4f8dff, corner: 0xffe14d, box: 0x3ee07a, grasp: 0xff4fd8 };

export class CloudView {
  constructor(container) {
    this.container = container;
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    container.appendChild(this.renderer.domElement);
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(0x000000);
    this.camera = new THREE.PerspectiveCamera(50, 4 / 3, 0.01, 50);
    // Look from behind the depth camera, slightly above: the camera frame has
    // y down, so the view's up is -y.
    this.camera.up.set(0, -1, 0);
    this.camera.position.set(0.6, -0.8, -0.6);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.target.set(0, 0, 1.2);
    this.controls.addEventListener('change', () => this.render());
    this.points = null;
    this.overlay = new THREE.Group();
    this.scene.add(this.overlay);
    this.cloudFrame = null; // frame id of the cloud on screen
    this.fetching = false;
    this.framed = false; // the orbit target was set from a cloud once
    new ResizeObserver(() => this.resize()).observe(container);
    this.resize();
  }

  resize() {
    const w = this.container.clientWidth || 640;
    const h = this.container.clientHeight || 480;
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.render();
  }

  render() { this.renderer.render(this.scene, this.camera); }

  // Shows a detection's overlay at once and its cloud when fetched (one fetch at a time).
  show(d) {
    this.drawOverlay(d);
    if (!d.cloud || this.fetching || this.cloudFrame === d.frame_id) return;
    this.fetching = true;
    getArrayBuffer(d.cloud.url)
      .then((buffer) => this.setCloud(decodeCloud(buffer), d.frame_id))
      .catch((e) => console.warn(e.message))
      .finally(() => { this.fetching = false; });
  }

  setCloud(cloud, frameId) {
    if (this.points) {
      this.scene.remove(this.points);
      this.points.geometry.dispose();
    }
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(cloud.positions, 3));
    let colors = cloud.colors;
    if (!colors) colors = depthColors(cloud.positions);
    geometry.setAttribute('color', new THREE.BufferAttribute(colors, 3));
    this.points = new THREE.Points(geometry,
      new THREE.PointsMaterial({ size: 0.004, vertexColors: true }));
    this.scene.add(this.points);
    this.cloudFrame = frameId;
    if (!this.framed && cloud.count > 0) {
      geometry.computeBoundingSphere();
      const { center, radius } = geometry.boundingSphere;
      this.controls.target.copy(center);
      this.camera.position.set(center.x + radius * 0.6, center.y - radius * 0.9, center.z - radius * 1.4);
      this.controls.update();
      this.framed = true;
    }
    this.render();
  }

  drawOverlay(d) {
    for (const child of [...this.overlay.children]) {
      this.overlay.remove(child);
      child.geometry?.dispose();
    }
    const lines = (pairs, color) => {
      const geometry = new THREE.BufferGeometry();
      geometry.setAttribute('position', new THREE.Float32BufferAttribute(pairs.flat(2), 3));
      this.overlay.add(new THREE.LineSegments(geometry, new THREE.LineBasicMaterial({ color })));
    };
    const dots = (points, color, size) => {
      const geometry = new THREE.BufferGeometry();
      geometry.setAttribute('position', new THREE.Float32BufferAttribute(points.flat(), 3));
      this.overlay.add(new THREE.Points(geometry, new THREE.PointsMaterial({ color, size })));
    };
    const boxEdges = [];
    for (const box of d.boxes) {
      const c = boxCorners(box.camera_T_box, d.box_dims);
      for (const [a, b] of BOX_EDGES) boxEdges.push([c[a], c[b]]);
    }
    lines(boxEdges, COLORS.box);
    lines(d.segments.map((s) => [s.end1, s.end2]), COLORS.segment);
    lines(d.boxes.map((b) => [b.grasp_centre, b.grasp_centre.map((x, j) => x + 0.08 * b.grasp_normal[j])]),
      COLORS.grasp);
    dots([...triples(d.edge_points || [])], COLORS.edge, 0.005);
    dots(d.corners, COLORS.corner, 0.015);
    dots(d.boxes.map((b) => b.grasp_centre), COLORS.grasp, 0.02);
    this.render();
  }
}

// Grey by depth (near = bright) for clouds without colour.
function depthColors(positions) {
  let near = Infinity;
  let far = -Infinity;
  for (let i = 2; i < positions.length; i += 3) {
    near = Math.min(near, positions[i]);
    far = Math.max(far, positions[i]);
  }
  const span = Math.max(far - near, 1e-3);
  const colors = new Float32Array(positions.length);
  for (let i = 0; i < positions.length; i += 3) {
    const g = 0.25 + 0.75 * (1 - (positions[i + 2] - near) / span);
    colors[i] = colors[i + 1] = colors[i + 2] = g;
  }
  return colors;
}
