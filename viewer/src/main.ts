// The htngtp viewer: loads a plan JSON (docs/plan-json.md), shows its scene in 3D and plays the
// plan. Source of the plan: `?plan=URL`, else `plan.json` beside the page (what `htngtp view`
// serves), or a file opened with the button or dropped on the page.

import './style.css';
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { CSS2DRenderer } from 'three/addons/renderers/CSS2DRenderer.js';
import { type Plan, PlanError, type Pose, parsePlanText } from './plan';
import { SceneView, type VisualStats } from './scene';
import { Timeline, type WorldState } from './timeline';
import { Ui } from './ui';

const BACKGROUND = new THREE.Color(0xb8c4d0);
/** Turns a ROS-style camera link (x forward, z up) into a three.js camera (looks along -z, y up). */
const EYE_TO_CAMERA = new THREE.Matrix4().makeBasis(
  new THREE.Vector3(0, -1, 0),
  new THREE.Vector3(0, 0, 1),
  new THREE.Vector3(-1, 0, 0),
);

interface Snapshot {
  step: number;
  time: number;
  objects: Record<string, Pose>;
  links: Record<string, Record<string, Pose>>;
}

interface PixelStats {
  width: number;
  height: number;
  mean: number;
  variance: number;
  /** Fraction of pixels that differ from the background colour. */
  nonBackground: number;
}

/** What the browser tests read and drive (window.__htngtp). */
export interface TestHook {
  readonly ready: boolean;
  readonly error: string | null;
  readonly objectCount: number;
  readonly agentCount: number;
  readonly linkCount: number;
  /** The links' visual meshes: loading, loaded, failed. */
  readonly visuals: VisualStats;
  readonly stepCount: number;
  readonly currentStep: number;
  readonly time: number;
  readonly duration: number;
  readonly playing: boolean;
  readonly camera: string;
  objectPose(name: string): Pose | null;
  linkPose(agent: string, link: string): Pose | null;
  cameraPose(): Pose;
  /** Everything at once: current step, time, and the rendered pose of every object and link. */
  snapshot(): Snapshot;
  stepTimes(): { start: number; end: number }[];
  play(speed?: number): void;
  pause(): void;
  seek(step: number): void;
  seekTime(t: number): void;
  seekFrame(step: number, trajectory: number, frame: number): void;
  setCamera(mode: string): void;
  pixelStats(): PixelStats;
  load(url: string): Promise<void>;
}

class App {
  readonly renderer: THREE.WebGLRenderer;
  readonly labels = new CSS2DRenderer();
  readonly scene = new THREE.Scene();
  readonly camera = new THREE.PerspectiveCamera(50, 1, 0.03, 200);
  readonly controls: OrbitControls;
  readonly ui: Ui;
  private readonly view: HTMLElement;
  private readonly sun: THREE.DirectionalLight;

  plan: Plan | null = null;
  sceneView: SceneView | null = null;
  timeline: Timeline | null = null;
  state: WorldState | null = null;
  t = 0;
  speed = 1;
  playing = false;
  cameraMode = 'orbit';
  ready = false;
  error: string | null = null;
  private dirty = true;
  private last = performance.now();

  constructor() {
    this.view = document.getElementById('view')!;
    this.ui = new Ui({
      seekStep: (i) => this.seekStep(i),
      seekFraction: (f) => this.seekTime(f * (this.timeline?.duration ?? 0)),
      togglePlay: () => (this.playing ? this.pause() : this.play()),
      step: (d) => this.stepBy(d),
      speed: (s) => (this.speed = s),
      camera: (m) => this.setCamera(m),
      openFile: (f) => void this.loadFile(f),
    });

    this.renderer = new THREE.WebGLRenderer({ antialias: true });
    this.renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
    this.renderer.shadowMap.enabled = true;
    this.renderer.shadowMap.type = THREE.PCFShadowMap;
    this.renderer.toneMapping = THREE.ACESFilmicToneMapping;
    this.renderer.toneMappingExposure = 1.05;
    this.view.prepend(this.renderer.domElement);
    this.labels.domElement.style.position = 'absolute';
    this.labels.domElement.style.inset = '0';
    this.labels.domElement.style.pointerEvents = 'none';
    this.view.append(this.labels.domElement);
    const labelsToggle = document.getElementById('labels-toggle') as HTMLInputElement;
    labelsToggle.addEventListener('change', () => (this.labels.domElement.hidden = !labelsToggle.checked));

    this.scene.background = BACKGROUND;
    this.camera.up.set(0, 0, 1);
    this.camera.position.set(-3, -6, 4);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.enableDamping = true;
    this.controls.dampingFactor = 0.12;
    this.controls.maxPolarAngle = Math.PI * 0.495;

    this.scene.add(new THREE.HemisphereLight(0xf2f6ff, 0x6b6358, 1.6));
    this.sun = new THREE.DirectionalLight(0xfff4e5, 2.4);
    this.sun.position.set(3, -4, 7);
    this.sun.castShadow = true;
    this.sun.shadow.mapSize.set(2048, 2048);
    this.sun.shadow.bias = -0.0005;
    this.sun.shadow.normalBias = 0.02;
    this.sun.shadow.radius = 3;
    this.scene.add(this.sun, this.sun.target);

    const floor = new THREE.Mesh(
      new THREE.PlaneGeometry(1, 1),
      new THREE.MeshStandardMaterial({ color: 0xd8d2c8, roughness: 0.95 }),
    );
    floor.name = 'floor';
    floor.receiveShadow = true;
    this.scene.add(floor);
    const grid = new THREE.GridHelper(1, 1, 0x9a948a, 0xb3ada3);
    grid.name = 'grid';
    grid.rotation.x = Math.PI / 2;
    grid.position.z = 0.001;
    this.scene.add(grid);

    new ResizeObserver(() => this.resize()).observe(this.view);
    this.resize();
    requestAnimationFrame((now) => this.frame(now));
  }

  /** Sizes floor, grid, shadow camera and orbit view to the scene's extent. */
  private fit(): void {
    const root = this.sceneView?.root;
    const box = root ? new THREE.Box3().setFromObject(root) : new THREE.Box3();
    if (box.isEmpty()) box.set(new THREE.Vector3(-2, -2, 0), new THREE.Vector3(2, 2, 1));
    const center = box.getCenter(new THREE.Vector3());
    const size = box.getSize(new THREE.Vector3());
    const radius = Math.max(size.length() / 2, 1);
    const floorSize = Math.ceil(Math.max(size.x, size.y) + 4);
    const floor = this.scene.getObjectByName('floor')!;
    floor.scale.set(floorSize, floorSize, 1);
    floor.position.set(center.x, center.y, 0);
    const grid = this.scene.getObjectByName('grid') as THREE.GridHelper;
    this.scene.remove(grid);
    grid.geometry.dispose();
    const g = new THREE.GridHelper(floorSize, floorSize * 2, 0x9a948a, 0xbdb7ad);
    g.name = 'grid';
    g.rotation.x = Math.PI / 2;
    g.position.set(Math.round(center.x), Math.round(center.y), 0.001);
    this.scene.add(g);
    const cam = this.sun.shadow.camera;
    cam.left = cam.bottom = -radius * 1.3;
    cam.right = cam.top = radius * 1.3;
    cam.near = 0.1;
    cam.far = 40;
    cam.updateProjectionMatrix();
    this.sun.target.position.copy(center);
    this.sun.position.copy(center).add(new THREE.Vector3(3, -4, 7));
    // Looking from the front-left, a little above, at the whole scene.
    this.controls.target.copy(center);
    const dir = new THREE.Vector3(0.5, -1, 0.75).normalize();
    const dist = radius / Math.sin(THREE.MathUtils.degToRad(this.camera.fov / 2)) * 0.8;
    this.camera.position.copy(center).addScaledVector(dir, dist);
    this.controls.update();
  }

  private resize(): void {
    const w = Math.max(this.view.clientWidth, 1);
    const h = Math.max(this.view.clientHeight, 1);
    this.renderer.setSize(w, h);
    this.labels.setSize(w, h);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.dirty = true;
  }

  async loadUrl(url: string): Promise<void> {
    let text: string;
    try {
      const res = await fetch(url, { cache: 'no-store' });
      if (!res.ok) {
        throw new PlanError(url, [
          `could not load the plan: HTTP ${res.status} ${res.statusText}`.trim(),
          'serve a plan with `htngtp view PLAN.json`, pass ?plan=URL, or open a file with "open plan…"',
        ]);
      }
      text = await res.text();
    } catch (e) {
      this.fail(e instanceof PlanError ? e : new PlanError(url, [`could not load the plan: ${String(e)}`]));
      return;
    }
    this.loadText(text, url, url);
  }

  async loadFile(file: File): Promise<void> {
    let text: string;
    try {
      text = await file.text();
    } catch (e) {
      this.fail(new PlanError(file.name, [`could not read the file: ${String(e)}`]));
      return;
    }
    this.loadText(text, file.name);
  }

  /** `base`: the plan's URL, for its visual meshes (null for a plan read from a file). */
  loadText(text: string, source: string, base: string | null = null): void {
    let plan: Plan;
    let view: SceneView;
    try {
      plan = parsePlanText(text, source);
      view = new SceneView(plan, base, () => {
        this.dirty = true;
      });
    } catch (e) {
      this.fail(e instanceof PlanError ? e : new PlanError(source, [`could not build the scene: ${String(e)}`]));
      return;
    }
    this.unload();
    this.plan = plan;
    this.sceneView = view;
    this.scene.add(view.root);
    this.timeline = new Timeline(plan);
    this.t = 0;
    this.ui.clearError();
    this.ui.setPlan(plan, this.timeline, source);
    const modes = [{ value: 'orbit', label: 'orbit' }];
    for (const a of plan.scene.agents) {
      if (a.eye_link !== null) modes.push({ value: `eye:${a.name}`, label: `${a.name}'s ${a.kind === 'human' ? 'eyes' : 'head camera'}` });
    }
    if (!modes.some((m) => m.value === this.cameraMode)) this.cameraMode = 'orbit';
    this.ui.setCameraModes(modes, this.cameraMode);
    this.error = null;
    this.fit();
    this.applyTime();
    this.render();
    this.ready = true;
    document.title = `htngtp · ${plan.domain} / ${plan.problem}`;
  }

  private unload(): void {
    this.pause();
    this.sceneView?.dispose();
    this.sceneView = null;
    this.plan = null;
    this.timeline = null;
    this.state = null;
    this.ready = false;
  }

  fail(e: PlanError): void {
    console.error(e.message);
    this.unload();
    this.ui.clearPlan();
    this.ui.showError(e.source, e.problems);
    this.error = e.message;
    this.fit();
    this.dirty = true;
  }

  play(speed?: number): void {
    if (speed !== undefined) this.speed = speed;
    if (this.timeline === null || this.timeline.duration <= 0) return;
    if (this.t >= this.timeline.duration) this.t = 0;
    this.playing = true;
    this.last = performance.now();
    this.applyTime();
  }

  pause(): void {
    this.playing = false;
    this.applyTime();
  }

  seekTime(t: number): void {
    if (this.timeline === null) return;
    this.t = Math.min(Math.max(t, 0), this.timeline.duration);
    this.applyTime();
  }

  seekStep(i: number): void {
    const span = this.timeline?.spans[i];
    if (span === undefined) return;
    this.pause();
    this.seekTime(span.start);
  }

  /** Previous / next step start; from inside a step, "previous" goes to its own start first. */
  stepBy(delta: number): void {
    const tl = this.timeline;
    if (tl === null || tl.spans.length === 0) return;
    const k = tl.stepAt(this.t);
    if (delta < 0) {
      const here = tl.spans[k]!.start;
      this.seekStep(this.t > here + 1e-6 && this.t < tl.duration ? k : Math.max(k - 1, 0));
    } else if (k + 1 < tl.spans.length) this.seekStep(k + 1);
    else {
      this.pause();
      this.seekTime(tl.duration);
    }
  }

  setCamera(mode: string): void {
    if (mode !== 'orbit' && !this.plan?.scene.agents.some((a) => `eye:${a.name}` === mode && a.eye_link !== null)) {
      throw new Error(`unknown camera "${mode}"`);
    }
    this.cameraMode = mode;
    this.ui.cameraSelect.value = mode;
    this.controls.enabled = mode === 'orbit';
    document.getElementById('camera-hint')!.hidden = mode !== 'orbit';
    if (mode === 'orbit') this.fit();
    this.dirty = true;
  }

  private applyTime(): void {
    const tl = this.timeline;
    const view = this.sceneView;
    if (tl === null || view === null || this.plan === null) return;
    const state = tl.stateAt(this.t);
    const highlight = new Set(state.held);
    if (state.step >= 0) {
      const s = this.plan.steps[state.step]!;
      for (const a of [...s.args, ...(s.gtp?.args ?? [])]) if (view.objects.has(a)) highlight.add(a);
    }
    view.apply(state, highlight);
    this.state = state;
    this.ui.update(state, this.t, tl.duration, this.playing);
    this.dirty = true;
  }

  private placeEyeCamera(): void {
    if (this.cameraMode === 'orbit' || this.plan === null || this.sceneView === null) return;
    const name = this.cameraMode.slice('eye:'.length);
    const agent = this.plan.scene.agents.find((a) => a.name === name);
    const link = agent?.eye_link ? this.sceneView.links.get(name)?.get(agent.eye_link) : undefined;
    if (link === undefined) return;
    link.updateWorldMatrix(true, false);
    const m = link.matrixWorld.clone().multiply(EYE_TO_CAMERA);
    m.decompose(this.camera.position, this.camera.quaternion, new THREE.Vector3());
    this.camera.updateMatrixWorld();
  }

  private frame(now: number): void {
    // rAF's timestamp is the frame's start: it can precede a `last` taken by play() just before.
    const dt = Math.min(Math.max((now - this.last) / 1000, 0), 0.1);
    this.last = now;
    if (this.playing && this.timeline !== null) {
      this.t += dt * this.speed;
      if (this.t >= this.timeline.duration) {
        this.t = this.timeline.duration;
        this.playing = false;
      }
      this.applyTime();
    }
    if (this.cameraMode === 'orbit' && this.controls.update()) this.dirty = true;
    if (this.dirty) {
      this.render();
      this.dirty = false;
    }
    requestAnimationFrame((n) => this.frame(n));
  }

  render(): void {
    this.placeEyeCamera();
    this.renderer.render(this.scene, this.camera);
    this.labels.render(this.scene, this.camera);
  }

  pixelStats(): PixelStats {
    this.render();
    const gl = this.renderer.getContext();
    const w = gl.drawingBufferWidth;
    const h = gl.drawingBufferHeight;
    const px = new Uint8Array(w * h * 4);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
    let sum = 0;
    let sum2 = 0;
    let other = 0;
    // The background as displayed (sRGB output of the linear clear colour).
    const bg = BACKGROUND.clone().convertLinearToSRGB();
    const br = Math.round(bg.r * 255);
    const bgG = Math.round(bg.g * 255);
    const bb = Math.round(bg.b * 255);
    for (let i = 0; i < px.length; i += 4) {
      const r = px[i]!;
      const g = px[i + 1]!;
      const b = px[i + 2]!;
      const y = 0.2126 * r + 0.7152 * g + 0.0722 * b;
      sum += y;
      sum2 += y * y;
      if (Math.abs(r - br) + Math.abs(g - bgG) + Math.abs(b - bb) > 12) other++;
    }
    const n = w * h;
    const mean = sum / n;
    return { width: w, height: h, mean, variance: sum2 / n - mean * mean, nonBackground: other / n };
  }

  cameraPose(): Pose {
    const p = this.camera.position;
    const q = this.camera.quaternion;
    return { t: [p.x, p.y, p.z], q: [q.x, q.y, q.z, q.w] };
  }
}

function showFatal(message: string): void {
  const panel = document.getElementById('error-panel');
  if (panel === null) return;
  document.getElementById('error-source')!.textContent = 'the viewer';
  const li = document.createElement('li');
  li.textContent = message;
  document.getElementById('error-list')!.replaceChildren(li);
  panel.hidden = false;
}

let app: App;
try {
  app = new App();
} catch (e) {
  // Typically no WebGL: say so rather than leave a blank page.
  showFatal(`could not start the 3D view: ${e instanceof Error ? e.message : String(e)}`);
  (window as unknown as { __htngtp: unknown }).__htngtp = { ready: false, error: String(e) };
  throw e;
}
window.addEventListener('error', (e) => showFatal(`unexpected error: ${e.message}`));
window.addEventListener('unhandledrejection', (e) => showFatal(`unexpected error: ${String(e.reason)}`));

const hook: TestHook = {
  get ready() { return app.ready; },
  get error() { return app.error; },
  get objectCount() { return app.sceneView?.objectsGroup.children.length ?? 0; },
  get agentCount() { return app.sceneView?.agentsGroup.children.length ?? 0; },
  get linkCount() { return app.sceneView?.linkCount ?? 0; },
  get visuals() {
    const v = app.sceneView?.visualStats;
    return v === undefined ? { pending: 0, links: 0, meshes: 0, failed: [] } : { ...v, failed: [...v.failed] };
  },
  get stepCount() { return app.plan?.steps.length ?? 0; },
  get currentStep() { return app.state?.step ?? -1; },
  get time() { return app.t; },
  get duration() { return app.timeline?.duration ?? 0; },
  get playing() { return app.playing; },
  get camera() { return app.cameraMode; },
  objectPose: (name) => app.sceneView?.objectPose(name) ?? null,
  linkPose: (agent, link) => app.sceneView?.linkPose(agent, link) ?? null,
  cameraPose: () => {
    app.render();
    return app.cameraPose();
  },
  snapshot: () => {
    const v = app.sceneView;
    const objects: Record<string, Pose> = {};
    const links: Record<string, Record<string, Pose>> = {};
    for (const name of v?.objects.keys() ?? []) objects[name] = v!.objectPose(name)!;
    for (const [agent, byLink] of v?.links ?? []) {
      links[agent] = {};
      for (const l of byLink.keys()) links[agent][l] = v!.linkPose(agent, l)!;
    }
    return { step: app.state?.step ?? -1, time: app.t, objects, links };
  },
  stepTimes: () => app.timeline?.spans.map((s) => ({ start: s.start, end: s.end })) ?? [],
  play: (speed) => app.play(speed),
  pause: () => app.pause(),
  seek: (i) => app.seekStep(i),
  seekTime: (t) => app.seekTime(t),
  seekFrame: (i, j, f) => {
    if (app.timeline === null) throw new Error('no plan loaded');
    app.pause();
    app.seekTime(app.timeline.frameTime(i, j, f));
  },
  setCamera: (m) => app.setCamera(m),
  pixelStats: () => app.pixelStats(),
  load: (url) => app.loadUrl(url),
};
(window as unknown as { __htngtp: TestHook }).__htngtp = hook;

const param = new URLSearchParams(location.search).get('plan');
void app.loadUrl(param ?? 'plan.json');
