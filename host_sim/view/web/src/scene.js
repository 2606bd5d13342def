// The 3D scene: the colon (displaced, regions coloured), the scope in it, the contact forces as
// arrows, the true tip and the box's estimate (its tip with its uncertainty, its stations).
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import { arcLengths, pointAtArc } from './run_data.js';

// The regions' palette of the plots (host_sim/plots/plot_run.py REGION_BASE, Okabe-Ito).
const kRegionColours = {
  rectum: 0xe69f00,
  sigmoid: 0x56b4e9,
  descending: 0x009e73,
  splenic_flexure: 0xf0e442,
  transverse: 0xcc79a7,
  hepatic_flexure: 0x0072b2,
  ascending: 0xd55e00,
  cecum: 0x999999,
};
const kScopeRadius_mm = 6.5;  // CF-Q160L's 13 mm shaft
const kRingSides = 14;
const kMaxArrows = 64;

/// Green below 5 N, amber to 10 N, red from 14 N (the box's warning and critical levels).
export function forceColour(force_N) {
  if (force_N >= 14) return 0xd62728;
  if (force_N >= 10) return 0xff7f0e;
  if (force_N >= 5) return 0xf1c40f;
  return 0x2ca02c;
}

/// A tube of rings around a polyline; its positions are rewritten when the polyline moves.
class RingTube {
  constructor(pointCount, radii, colours, material) {
    this.pointCount = pointCount;
    this.radii = radii;
    const geometry = new THREE.BufferGeometry();
    const positions = new Float32Array(pointCount * kRingSides * 3);
    geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
    if (colours) {
      const c = new Float32Array(pointCount * kRingSides * 3);
      const colour = new THREE.Color();
      for (let i = 0; i < pointCount; i++) {
        colour.setHex(colours[i]);
        for (let s = 0; s < kRingSides; s++) colour.toArray(c, (i * kRingSides + s) * 3);
      }
      geometry.setAttribute('color', new THREE.BufferAttribute(c, 3));
    }
    const index = [];
    for (let i = 0; i + 1 < pointCount; i++)
      for (let s = 0; s < kRingSides; s++) {
        const a = i * kRingSides + s;
        const b = i * kRingSides + ((s + 1) % kRingSides);
        index.push(a, b, a + kRingSides, b, b + kRingSides, a + kRingSides);
      }
    geometry.setIndex(index);
    this.mesh = new THREE.Mesh(geometry, material);
  }

  /// Rings perpendicular to the polyline, carried along it by parallel transport.
  update(points) {
    const n = Math.min(points.length, this.pointCount);
    const pos = this.mesh.geometry.attributes.position.array;
    const t = new THREE.Vector3();
    const normal = new THREE.Vector3(0, 0, 1);
    const binormal = new THREE.Vector3();
    const p = new THREE.Vector3();
    const prev = new THREE.Vector3();
    for (let i = 0; i < n; i++) {
      const a = points[Math.max(i - 1, 0)];
      const b = points[Math.min(i + 1, n - 1)];
      t.set(b[0] - a[0], b[1] - a[1], b[2] - a[2]);
      if (t.lengthSq() === 0) t.set(1, 0, 0);
      t.normalize();
      if (i === 0) {
        normal.set(0, 0, 1);
        if (Math.abs(normal.dot(t)) > 0.9) normal.set(0, 1, 0);
      } else {
        normal.copy(prev);
      }
      normal.addScaledVector(t, -normal.dot(t)).normalize();
      prev.copy(normal);
      binormal.crossVectors(t, normal);
      const r = this.radii[Math.min(i, this.radii.length - 1)];
      for (let s = 0; s < kRingSides; s++) {
        const angle = (2 * Math.PI * s) / kRingSides;
        p.set(points[i][0], points[i][1], points[i][2])
          .addScaledVector(normal, r * Math.cos(angle))
          .addScaledVector(binormal, r * Math.sin(angle));
        p.toArray(pos, (i * kRingSides + s) * 3);
      }
    }
    // Rings past the polyline's end collapse onto its last point (a scope not yet inserted).
    for (let i = n; i < this.pointCount; i++)
      for (let s = 0; s < kRingSides; s++) {
        const last = points[n - 1] || [0, 0, 0];
        pos.set(last, (i * kRingSides + s) * 3);
      }
    this.mesh.geometry.attributes.position.needsUpdate = true;
    this.mesh.geometry.computeVertexNormals();
    this.mesh.geometry.computeBoundingSphere();
  }
}

export class RunScene {
  constructor(container, data) {
    this.data = data;
    this.restArcs = arcLengths(data.colon.centerline_mm);
    // No multisampling: software WebGL (a machine without a GPU) draws several times faster.
    this.renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    this.renderer.setClearColor(0x101418);
    container.appendChild(this.renderer.domElement);
    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(40, 1, 1, 20000);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.cameraMoved = true;
    this.controls.addEventListener('change', () => { this.cameraMoved = true; });
    this.scene.add(new THREE.AmbientLight(0xffffff, 0.6));
    const sun = new THREE.DirectionalLight(0xffffff, 1.6);
    sun.position.set(300, 800, 900);
    this.scene.add(sun);

    const colon = data.colon;
    const colours = colon.region.map((r) => kRegionColours[r] ?? 0x999999);
    this.colon = new RingTube(
      colon.centerline_mm.length,
      colon.inner_radius_mm,
      colours,
      new THREE.MeshStandardMaterial({
        vertexColors: true, transparent: true, opacity: 0.28, side: THREE.DoubleSide,
        depthWrite: false,
      }),
    );
    this.colon.update(colon.centerline_mm);
    this.scene.add(this.colon.mesh);

    const maxScopePoints = data.scope_max_points ?? Math.max(2, ...data.frames.map((f) => f.scope_mm.length));
    this.scope = new RingTube(
      maxScopePoints,
      [kScopeRadius_mm],
      null,
      new THREE.MeshStandardMaterial({ color: 0xdddddd, metalness: 0.1, roughness: 0.5 }),
    );
    this.scene.add(this.scope.mesh);

    this.trueTip = new THREE.Mesh(
      new THREE.SphereGeometry(8, 20, 14),
      new THREE.MeshStandardMaterial({ color: 0xffffff, emissive: 0x333333 }),
    );
    this.scene.add(this.trueTip);
    this.boxTip = new THREE.Mesh(
      new THREE.SphereGeometry(7, 20, 14),
      new THREE.MeshStandardMaterial({ color: 0x00bcd4, emissive: 0x004050 }),
    );
    this.scene.add(this.boxTip);
    this.boxTipSpread = new THREE.Mesh(
      new THREE.SphereGeometry(1, 24, 16),
      new THREE.MeshBasicMaterial({ color: 0x00bcd4, transparent: true, opacity: 0.18, depthWrite: false }),
    );
    this.scene.add(this.boxTipSpread);

    this.stations = [];
    this.arrows = [];
    for (let k = 0; k < kMaxArrows; k++) {
      const arrow = new THREE.ArrowHelper(new THREE.Vector3(1, 0, 0), new THREE.Vector3(), 10, 0xffffff, 6, 4);
      arrow.visible = false;
      this.scene.add(arrow);
      this.arrows.push(arrow);
    }
    this.frameIndex = -1;
    this.frameCentreline = colon.centerline_mm;
    this.fitCamera(colon.centerline_mm);
    this.resize(container);
  }

  fitCamera(points) {
    const box = new THREE.Box3();
    for (const p of points) box.expandByPoint(new THREE.Vector3(p[0], p[1], p[2]));
    const centre = box.getCenter(new THREE.Vector3());
    const size = box.getSize(new THREE.Vector3()).length();
    // Frontal view, as the patients' gallery draws it (host_sim/plots/plot_patients.py): x the
    // patient's left, to the right as on a radiograph; y cranial, up.
    this.camera.position.set(centre.x, centre.y, centre.z + 1.3 * size);
    this.camera.up.set(0, 1, 0);
    this.controls.target.copy(centre);
    this.controls.update();
  }

  resize(container) {
    const w = container.clientWidth || 640;
    const h = container.clientHeight || 480;
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
  }

  /// Shows the frame nearest before time t and the box's estimate at that time.
  show(frameIndex, estimate) {
    const frame = this.data.frames[frameIndex];
    if (frame && frameIndex !== this.frameIndex) {
      this.frameIndex = frameIndex;
      if (frame.colon_mm && frame.colon_mm.length === this.data.colon.centerline_mm.length) {
        this.frameCentreline = frame.colon_mm;
        this.colon.update(frame.colon_mm);
      }
      if (frame.scope_mm.length >= 2) this.scope.update(frame.scope_mm);
      this.scope.mesh.visible = frame.scope_mm.length >= 2;
      this.showContacts(frame.contacts || []);
    }
    if (estimate) this.showEstimate(estimate);
  }

  showContacts(contacts) {
    const sorted = [...contacts].sort((a, b) => b.normal_force_N - a.normal_force_N);
    for (let k = 0; k < this.arrows.length; k++) {
      const arrow = this.arrows[k];
      const c = sorted[k];
      arrow.visible = c !== undefined;
      if (!c) continue;
      const f = new THREE.Vector3(...c.force_N);
      const length = 8 + 6 * Math.min(c.normal_force_N, 20);
      // The arrow shows the wall's force on the scope, ending at the contact.
      const dir = f.lengthSq() > 0 ? f.clone().normalize() : new THREE.Vector3(0, 0, 1);
      const origin = new THREE.Vector3(...c.position_mm).addScaledVector(dir, -length);
      arrow.position.copy(origin);
      arrow.setDirection(dir);
      arrow.setLength(length, 6, 4);
      arrow.setColor(forceColour(c.normal_force_N));
    }
  }

  showEstimate(estimate) {
    const line = this.frameCentreline;
    // The true tip: the scope's last node where there is a shape, else the truth's path (none on
    // the box's own page).
    this.trueTip.visible = Number.isFinite(estimate.true_tip_path_mm);
    if (this.trueTip.visible)
      this.trueTip.position.set(...pointAtArc(line, this.restArcs, estimate.true_tip_path_mm));
    const frame = this.data.frames[this.frameIndex];
    if (frame && frame.scope_mm.length > 0) this.trueTip.position.set(...frame.scope_mm[frame.scope_mm.length - 1]);
    this.boxTip.visible = Number.isFinite(estimate.box_tip_path_mm);
    if (this.boxTip.visible) {
      this.boxTip.position.set(...pointAtArc(line, this.restArcs, estimate.box_tip_path_mm));
      this.boxTipSpread.position.copy(this.boxTip.position);
      const sd = Number.isFinite(estimate.box_tip_sd_mm) ? Math.max(estimate.box_tip_sd_mm, 7) : 7;
      this.boxTipSpread.scale.setScalar(sd);
    }
    this.boxTipSpread.visible = this.boxTip.visible;
    const stations = estimate.stations || [];
    while (this.stations.length < stations.length) {
      const m = new THREE.Mesh(new THREE.SphereGeometry(4.5, 12, 8), new THREE.MeshBasicMaterial());
      this.scene.add(m);
      this.stations.push(m);
    }
    this.stations.forEach((m, k) => {
      const s = stations[k];
      m.visible = s !== undefined && Number.isFinite(s.path_mm);
      if (!m.visible) return;
      m.position.set(...pointAtArc(line, this.restArcs, s.path_mm));
      m.material.color.setHex(forceColour(s.normal_N));
    });
  }

  render() {
    this.controls.update();
    this.renderer.render(this.scene, this.camera);
  }
}
