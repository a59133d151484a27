// The plan JSON (docs/plan-json.md): its types, and a validator that turns an untrusted parsed
// document into a typed `Plan` or a list of errors, each with the key path where it was found.

export type Vec3 = [number, number, number];
export type Quat = [number, number, number, number];
export type Color = [number, number, number];

/** A rigid transform in the world frame (z up): translation and unit quaternion (x, y, z, w). */
export interface Pose {
  t: Vec3;
  q: Quat;
}

export type Shape =
  | { box: { half_extents: Vec3 } }
  | { cylinder: { radius: number; half_height: number } }
  | { capsule: { a: Vec3; b: Vec3; radius: number } }
  | { mesh: { vertices: Vec3[]; triangles: [number, number, number][] } };

export interface SceneObject {
  name: string;
  movable: boolean;
  color: Color | null;
  /** The object's geometry in its frame: its `shape` (at identity) and its `parts`, if any. */
  parts: LinkShape[];
  pose: Pose;
}

export interface LinkShape {
  shape: Shape;
  pose: Pose;
  color: Color | null;
}

/** A URDF visual mesh of a link: a file to load (STL, COLLADA, OBJ), for display only. */
export interface Visual {
  /** Where the file is served, relative to the plan's URL (`mesh/3.dae`). */
  uri: string;
  /** The mesh's pose in the link frame. */
  pose: Pose;
  scale: Vec3;
  /** The URDF material's colour, or null (the file's own materials, or the link's colour). */
  color: Color | null;
}

export interface Link {
  name: string;
  shapes: LinkShape[];
  /** The link's visual meshes (may be empty: the link is drawn by its shapes). */
  visuals: Visual[];
}

export interface Agent {
  name: string;
  kind: 'robot' | 'human';
  eye_link: string | null;
  links: Link[];
  link_poses: Record<string, Pose>;
}

export interface TreeNode {
  id: number;
  /** Compound task name, or null for an action. */
  task: string | null;
  /** Action name, or null for a compound task. */
  action: string | null;
  args: string[];
  method: string | null;
  children: number[];
  step: number | null;
}

export interface Frame {
  link_poses: Record<string, Pose>;
  held_pose: Pose | null;
  /** Seconds from the trajectory's start (`t`, the timed point's `time_from_start`); null in older plans. */
  t: number | null;
}

export interface Trajectory {
  agent: string;
  label: string;
  holding: string | null;
  frames: Frame[];
}

export interface GtpResult {
  task: string;
  args: string[];
  summary: Record<string, unknown>;
  stats: Record<string, unknown>;
  trajectories: Trajectory[];
}

export type Literal = string[];

export interface Step {
  index: number;
  id: number;
  action: string;
  args: string[];
  added: Literal[];
  deleted: Literal[];
  gtp: GtpResult | null;
  object_poses: Record<string, Pose>;
}

export interface Plan {
  format: 'htngtp-plan';
  version: number;
  domain: string;
  problem: string;
  status: 'solved' | 'unsolvable' | 'limit';
  message: string | null;
  scene: { objects: SceneObject[]; agents: Agent[] };
  tree: TreeNode[];
  root: number[];
  steps: Step[];
  stats: Record<string, unknown>;
}

export const FORMAT = 'htngtp-plan';
export const SUPPORTED_VERSION = 1;

/** A plan that could not be read: every problem found, each starting with its key path. */
export class PlanError extends Error {
  constructor(
    readonly source: string,
    readonly problems: string[],
  ) {
    super(`${source}: ${problems.length === 1 ? problems[0] : `${problems.length} problems: ${problems.join('; ')}`}`);
    this.name = 'PlanError';
  }
}

/** Parses JSON text, reporting a syntax error with its line and column. */
export function parsePlanText(text: string, source: string): Plan {
  let doc: unknown;
  try {
    doc = JSON.parse(text);
  } catch (e) {
    throw new PlanError(source, [`not valid JSON: ${jsonErrorWhere(text, e)}`]);
  }
  return validatePlan(doc, source);
}

function jsonErrorWhere(text: string, e: unknown): string {
  const msg = e instanceof Error ? e.message : String(e);
  if (text.trim() === '') return 'the file is empty';
  if (/line \d+ column \d+/.test(msg)) return msg;
  const m = /position (\d+)/.exec(msg);
  // Without a position (a truncated file), the error is at the end.
  const pos = m ? Number(m[1]) : /end of JSON/i.test(msg) ? text.length : null;
  if (pos === null) return msg;
  const before = text.slice(0, pos);
  const line = before.split('\n').length;
  const column = pos - before.lastIndexOf('\n');
  return `${msg} (line ${line} column ${column})`;
}

const MAX_PROBLEMS = 20;
const IDENTITY: Pose = { t: [0, 0, 0], q: [0, 0, 0, 1] };

/** Checks a parsed document against the contract and the invariants of docs/plan-json.md. */
export function validatePlan(doc: unknown, source: string): Plan {
  const v = new Validator();
  const plan = v.plan(doc);
  if (v.problems.length > 0 || plan === null) {
    throw new PlanError(source, v.problems.length > 0 ? v.problems : ['not a plan']);
  }
  return plan;
}

type Obj = Record<string, unknown>;

class Validator {
  problems: string[] = [];

  fail(path: string, what: string): null {
    if (this.problems.length < MAX_PROBLEMS) this.problems.push(`${path || '(document)'}: ${what}`);
    else if (this.problems.length === MAX_PROBLEMS) this.problems.push('… more problems not shown');
    return null;
  }

  obj(x: unknown, path: string): Obj | null {
    if (typeof x !== 'object' || x === null || Array.isArray(x)) return this.fail(path, `expected an object, found ${kindOf(x)}`);
    return x as Obj;
  }

  field(o: Obj, key: string, path: string): unknown {
    if (!(key in o)) {
      this.fail(path ? `${path}.${key}` : key, 'missing');
      return undefined;
    }
    return o[key];
  }

  str(x: unknown, path: string): string | null {
    if (typeof x !== 'string') return this.fail(path, `expected a string, found ${kindOf(x)}`);
    return x;
  }

  num(x: unknown, path: string): number | null {
    if (typeof x !== 'number' || !Number.isFinite(x)) return this.fail(path, `expected a finite number, found ${kindOf(x)}`);
    return x;
  }

  int(x: unknown, path: string): number | null {
    if (typeof x !== 'number' || !Number.isInteger(x)) return this.fail(path, `expected an integer, found ${kindOf(x)}`);
    return x;
  }

  arr(x: unknown, path: string): unknown[] | null {
    if (!Array.isArray(x)) return this.fail(path, `expected an array, found ${kindOf(x)}`);
    return x;
  }

  nums(x: unknown, n: number, path: string): number[] | null {
    const a = this.arr(x, path);
    if (a === null) return null;
    if (a.length !== n) return this.fail(path, `expected ${n} numbers, found ${a.length}`);
    const out: number[] = [];
    for (let i = 0; i < n; i++) {
      const v = this.num(a[i], `${path}[${i}]`);
      if (v === null) return null;
      out.push(v);
    }
    return out;
  }

  strs(x: unknown, path: string): string[] | null {
    const a = this.arr(x, path);
    if (a === null) return null;
    const out: string[] = [];
    a.forEach((s, i) => {
      const v = this.str(s, `${path}[${i}]`);
      if (v !== null) out.push(v);
    });
    return out.length === a.length ? out : null;
  }

  pose(x: unknown, path: string): Pose | null {
    const o = this.obj(x, path);
    if (o === null) return null;
    const t = this.nums(this.field(o, 't', path), 3, `${path}.t`);
    const q = this.nums(this.field(o, 'q', path), 4, `${path}.q`);
    if (t === null || q === null) return null;
    const n = Math.hypot(...q);
    if (Math.abs(n - 1) > 1e-3) return this.fail(`${path}.q`, `expected a unit quaternion, its norm is ${n.toPrecision(4)}`);
    return { t: t as Vec3, q: q.map((c) => c / n) as Quat };
  }

  color(x: unknown, path: string): Color | null {
    if (x === undefined || x === null) return null;
    const c = this.nums(x, 3, path);
    if (c === null) return null;
    if (c.some((v) => v < 0 || v > 1)) return this.fail(path, 'expected RGB components in [0, 1]');
    return c as Color;
  }

  positive(x: unknown, path: string): number | null {
    const v = this.num(x, path);
    if (v === null) return null;
    if (v <= 0) return this.fail(path, `expected a positive number, found ${v}`);
    return v;
  }

  shape(x: unknown, path: string): Shape | null {
    const o = this.obj(x, path);
    if (o === null) return null;
    const keys = Object.keys(o);
    if (keys.length !== 1) return this.fail(path, `expected exactly one of box, cylinder, capsule, mesh; found ${keys.length === 0 ? 'none' : keys.join(', ')}`);
    const kind = keys[0]!;
    const p = `${path}.${kind}`;
    const body = this.obj(o[kind], p);
    if (body === null) return null;
    switch (kind) {
      case 'box': {
        const h = this.nums(this.field(body, 'half_extents', p), 3, `${p}.half_extents`);
        if (h === null) return null;
        if (h.some((v) => v <= 0)) return this.fail(`${p}.half_extents`, 'expected positive half extents');
        return { box: { half_extents: h as Vec3 } };
      }
      case 'cylinder': {
        const radius = this.positive(this.field(body, 'radius', p), `${p}.radius`);
        const hh = this.positive(this.field(body, 'half_height', p), `${p}.half_height`);
        return radius === null || hh === null ? null : { cylinder: { radius, half_height: hh } };
      }
      case 'capsule': {
        const a = this.nums(this.field(body, 'a', p), 3, `${p}.a`);
        const b = this.nums(this.field(body, 'b', p), 3, `${p}.b`);
        const radius = this.positive(this.field(body, 'radius', p), `${p}.radius`);
        return a === null || b === null || radius === null ? null : { capsule: { a: a as Vec3, b: b as Vec3, radius } };
      }
      case 'mesh': {
        const vs = this.arr(this.field(body, 'vertices', p), `${p}.vertices`);
        const ts = this.arr(this.field(body, 'triangles', p), `${p}.triangles`);
        if (vs === null || ts === null) return null;
        const vertices: Vec3[] = [];
        for (let i = 0; i < vs.length; i++) {
          const v = this.nums(vs[i], 3, `${p}.vertices[${i}]`);
          if (v === null) return null;
          vertices.push(v as Vec3);
        }
        const triangles: [number, number, number][] = [];
        for (let i = 0; i < ts.length; i++) {
          const t = this.nums(ts[i], 3, `${p}.triangles[${i}]`);
          if (t === null) return null;
          if (t.some((k) => !Number.isInteger(k) || k < 0 || k >= vertices.length)) {
            return this.fail(`${p}.triangles[${i}]`, `expected vertex indices in 0..${vertices.length - 1}`);
          }
          triangles.push(t as [number, number, number]);
        }
        if (triangles.length === 0) return this.fail(`${p}.triangles`, 'expected at least one triangle');
        return { mesh: { vertices, triangles } };
      }
      default:
        return this.fail(path, `unknown shape "${kind}" (expected box, cylinder, capsule or mesh)`);
    }
  }

  /** A list of `{ shape, pose?, color? }`, poses in the owner's frame. */
  shapes(x: unknown, p: string): LinkShape[] | null {
    const a = this.arr(x, p);
    if (a === null) return null;
    const out: LinkShape[] = [];
    a.forEach((s, j) => {
      const sp = `${p}[${j}]`;
      const so = this.obj(s, sp);
      if (so === null) return;
      const shape = this.shape(this.field(so, 'shape', sp), `${sp}.shape`);
      const pose = so['pose'] === undefined || so['pose'] === null ? IDENTITY : this.pose(so['pose'], `${sp}.pose`);
      const color = this.color(so['color'], `${sp}.color`);
      if (shape !== null && pose !== null) out.push({ shape, pose, color });
    });
    return out.length === a.length ? out : null;
  }

  /** A link's optional `visuals`: `{ uri, pose?, scale?, color? }` each. */
  visuals(x: unknown, p: string): Visual[] {
    if (x === undefined || x === null) return [];
    const a = this.arr(x, p);
    if (a === null) return [];
    const out: Visual[] = [];
    a.forEach((v, j) => {
      const vp = `${p}[${j}]`;
      const vo = this.obj(v, vp);
      if (vo === null) return;
      const uri = this.str(this.field(vo, 'uri', vp), `${vp}.uri`);
      const pose = vo['pose'] === undefined || vo['pose'] === null ? IDENTITY : this.pose(vo['pose'], `${vp}.pose`);
      const scale = vo['scale'] === undefined || vo['scale'] === null ? [1, 1, 1] : this.nums(vo['scale'], 3, `${vp}.scale`);
      if (scale !== null && scale.some((c) => c === 0)) this.fail(`${vp}.scale`, 'expected non-zero scale factors');
      const color = this.color(vo['color'], `${vp}.color`);
      if (uri !== null && pose !== null && scale !== null) out.push({ uri, pose, scale: scale as Vec3, color });
    });
    return out;
  }

  plan(doc: unknown): Plan | null {
    const root = this.obj(doc, '');
    if (root === null) return null;
    const format = root['format'];
    if (format !== FORMAT) {
      return this.fail('format', `expected "${FORMAT}", found ${format === undefined ? 'nothing' : JSON.stringify(format)}: this is not an htngtp plan JSON`);
    }
    const version = root['version'];
    if (version !== SUPPORTED_VERSION) {
      return this.fail('version', `this viewer reads version ${SUPPORTED_VERSION}, found ${JSON.stringify(version ?? null)}`);
    }
    const domain = this.str(this.field(root, 'domain', ''), 'domain');
    const problem = this.str(this.field(root, 'problem', ''), 'problem');
    const status = this.field(root, 'status', '');
    if (status !== undefined && status !== 'solved' && status !== 'unsolvable' && status !== 'limit') {
      this.fail('status', `expected "solved", "unsolvable" or "limit", found ${JSON.stringify(status)}`);
    }
    const message = root['message'] === undefined || root['message'] === null ? null : this.str(root['message'], 'message');

    const scene = this.scene(this.field(root, 'scene', ''));
    if (scene === null) return null;
    const objectNames = new Set(scene.objects.map((o) => o.name));
    const agentsByName = new Map(scene.agents.map((a) => [a.name, a]));

    const steps = this.steps(this.field(root, 'steps', ''), objectNames, agentsByName);
    const tree = this.tree(this.field(root, 'tree', ''), steps);
    const rootIds = this.arr(this.field(root, 'root', ''), 'root');
    const ids = new Set((tree ?? []).map((n) => n.id));
    const rootList: number[] = [];
    rootIds?.forEach((r, i) => {
      const id = this.int(r, `root[${i}]`);
      if (id === null) return;
      if (!ids.has(id)) this.fail(`root[${i}]`, `id ${id} is not in tree`);
      rootList.push(id);
    });
    const stats = root['stats'] === undefined || root['stats'] === null ? {} : this.obj(root['stats'], 'stats');

    if (domain === null || problem === null || steps === null || tree === null || stats === null) return null;
    return {
      format: FORMAT,
      version: SUPPORTED_VERSION,
      domain,
      problem,
      status: status as Plan['status'],
      message,
      scene,
      tree,
      root: rootList,
      steps,
      stats,
    };
  }

  scene(x: unknown): Plan['scene'] | null {
    const o = this.obj(x, 'scene');
    if (o === null) return null;
    const objs = this.arr(this.field(o, 'objects', 'scene'), 'scene.objects') ?? [];
    const objects: SceneObject[] = [];
    const names = new Set<string>();
    objs.forEach((item, i) => {
      const p = `scene.objects[${i}]`;
      const ob = this.obj(item, p);
      if (ob === null) return;
      const name = this.str(this.field(ob, 'name', p), `${p}.name`);
      const movable = ob['movable'] === undefined ? false : ob['movable'];
      if (typeof movable !== 'boolean') this.fail(`${p}.movable`, `expected true or false, found ${kindOf(movable)}`);
      const color = this.color(ob['color'], `${p}.color`);
      // Geometry: a `shape`, or `parts` (shapes posed in the object frame), or both.
      let parts: LinkShape[] | null = [];
      if (!('shape' in ob) && !('parts' in ob)) {
        this.fail(`${p}.shape`, 'missing (an object needs a "shape" or "parts")');
        parts = null;
      }
      if ('shape' in ob) {
        const shape = this.shape(ob['shape'], `${p}.shape`);
        if (shape === null) parts = null;
        else parts?.push({ shape, pose: IDENTITY, color });
      }
      if ('parts' in ob) {
        const more = this.shapes(ob['parts'], `${p}.parts`);
        if (more === null) parts = null;
        else parts?.push(...more.map((s) => ({ ...s, color: s.color ?? color })));
      }
      const pose = this.pose(this.field(ob, 'pose', p), `${p}.pose`);
      if (name !== null) {
        if (names.has(name)) this.fail(`${p}.name`, `"${name}" is declared twice`);
        names.add(name);
      }
      if (name !== null && parts !== null && pose !== null && typeof movable === 'boolean') {
        objects.push({ name, movable, color, parts, pose });
      }
    });
    const ags = this.arr(this.field(o, 'agents', 'scene'), 'scene.agents') ?? [];
    const agents: Agent[] = [];
    ags.forEach((item, i) => {
      const agent = this.agent(item, `scene.agents[${i}]`);
      if (agent === null) return;
      if (names.has(agent.name)) this.fail(`scene.agents[${i}].name`, `"${agent.name}" is also the name of an object or agent`);
      names.add(agent.name);
      agents.push(agent);
    });
    return { objects, agents };
  }

  agent(x: unknown, p: string): Agent | null {
    const o = this.obj(x, p);
    if (o === null) return null;
    const name = this.str(this.field(o, 'name', p), `${p}.name`);
    const kind = this.field(o, 'kind', p);
    if (kind !== undefined && kind !== 'robot' && kind !== 'human') this.fail(`${p}.kind`, `expected "robot" or "human", found ${JSON.stringify(kind)}`);
    const eye = o['eye_link'] === undefined || o['eye_link'] === null ? null : this.str(o['eye_link'], `${p}.eye_link`);
    const ls = this.arr(this.field(o, 'links', p), `${p}.links`) ?? [];
    const links: Link[] = [];
    const linkNames = new Set<string>();
    ls.forEach((item, i) => {
      const lp = `${p}.links[${i}]`;
      const lo = this.obj(item, lp);
      if (lo === null) return;
      const ln = this.str(this.field(lo, 'name', lp), `${lp}.name`);
      if (ln === null) return;
      if (linkNames.has(ln)) this.fail(`${lp}.name`, `link "${ln}" is declared twice`);
      linkNames.add(ln);
      links.push({
        name: ln,
        shapes: this.shapes(this.field(lo, 'shapes', lp), `${lp}.shapes`) ?? [],
        visuals: this.visuals(lo['visuals'], `${lp}.visuals`),
      });
    });
    if (eye !== null && !linkNames.has(eye)) this.fail(`${p}.eye_link`, `"${eye}" is not one of the agent's links`);
    const link_poses = this.linkPoses(this.field(o, 'link_poses', p), `${p}.link_poses`, linkNames);
    if (name === null || link_poses === null) return null;
    return { name, kind: kind === 'human' ? 'human' : 'robot', eye_link: eye, links, link_poses };
  }

  /** Link poses of one agent: every key a declared link, and every link present. */
  linkPoses(x: unknown, p: string, links: Set<string>): Record<string, Pose> | null {
    const o = this.obj(x, p);
    if (o === null) return null;
    const out: Record<string, Pose> = {};
    let ok = true;
    for (const [k, v] of Object.entries(o)) {
      if (!links.has(k)) {
        this.fail(`${p}.${k}`, `unknown link "${k}" (the agent's links: ${[...links].join(', ')})`);
        ok = false;
        continue;
      }
      const pose = this.pose(v, `${p}.${k}`);
      if (pose === null) ok = false;
      else out[k] = pose;
    }
    const missing = [...links].filter((l) => !(l in o));
    if (missing.length > 0) {
      this.fail(p, `missing the pose of link${missing.length > 1 ? 's' : ''} ${missing.join(', ')}`);
      ok = false;
    }
    return ok ? out : null;
  }

  steps(x: unknown, objects: Set<string>, agents: Map<string, Agent>): Step[] | null {
    const a = this.arr(x, 'steps');
    if (a === null) return null;
    const out: Step[] = [];
    let ok = true;
    a.forEach((item, i) => {
      const s = this.step(item, i, objects, agents);
      if (s === null) ok = false;
      else out.push(s);
    });
    return ok ? out : null;
  }

  literals(x: unknown, p: string): Literal[] | null {
    const a = this.arr(x, p);
    if (a === null) return null;
    const out: Literal[] = [];
    for (let i = 0; i < a.length; i++) {
      const l = this.strs(a[i], `${p}[${i}]`);
      if (l === null) return null;
      if (l.length === 0) return this.fail(`${p}[${i}]`, 'expected a predicate name and its arguments');
      out.push(l);
    }
    return out;
  }

  step(x: unknown, i: number, objects: Set<string>, agents: Map<string, Agent>): Step | null {
    const p = `steps[${i}]`;
    const o = this.obj(x, p);
    if (o === null) return null;
    const index = this.int(this.field(o, 'index', p), `${p}.index`);
    if (index !== null && index !== i) this.fail(`${p}.index`, `expected ${i} (steps are listed in plan order), found ${index}`);
    const id = this.int(this.field(o, 'id', p), `${p}.id`);
    const action = this.str(this.field(o, 'action', p), `${p}.action`);
    const args = this.strs(this.field(o, 'args', p), `${p}.args`);
    const added = this.literals(this.field(o, 'added', p), `${p}.added`);
    const deleted = this.literals(this.field(o, 'deleted', p), `${p}.deleted`);
    const gtpRaw = o['gtp'];
    const gtp = gtpRaw === undefined || gtpRaw === null ? null : this.gtp(gtpRaw, `${p}.gtp`, objects, agents);
    const gtpOk = gtpRaw === undefined || gtpRaw === null || gtp !== null;
    const posesRaw = o['object_poses'] === undefined ? {} : this.obj(o['object_poses'], `${p}.object_poses`);
    const object_poses: Record<string, Pose> = {};
    let posesOk = posesRaw !== null;
    for (const [name, v] of Object.entries(posesRaw ?? {})) {
      if (!objects.has(name)) {
        this.fail(`${p}.object_poses.${name}`, `unknown object "${name}" (not declared in scene.objects)`);
        posesOk = false;
        continue;
      }
      const pose = this.pose(v, `${p}.object_poses.${name}`);
      if (pose === null) posesOk = false;
      else object_poses[name] = pose;
    }
    if (index === null || id === null || action === null || args === null || added === null || deleted === null || !gtpOk || !posesOk) return null;
    return { index, id, action, args, added, deleted, gtp, object_poses };
  }

  gtp(x: unknown, p: string, objects: Set<string>, agents: Map<string, Agent>): GtpResult | null {
    const o = this.obj(x, p);
    if (o === null) return null;
    const task = this.str(this.field(o, 'task', p), `${p}.task`);
    const args = this.strs(this.field(o, 'args', p), `${p}.args`);
    const summary = o['summary'] === undefined || o['summary'] === null ? {} : this.obj(o['summary'], `${p}.summary`);
    const stats = o['stats'] === undefined || o['stats'] === null ? {} : this.obj(o['stats'], `${p}.stats`);
    const ts = this.arr(o['trajectories'] ?? [], `${p}.trajectories`) ?? [];
    const trajectories: Trajectory[] = [];
    let ok = true;
    ts.forEach((item, k) => {
      const tr = this.trajectory(item, `${p}.trajectories[${k}]`, objects, agents);
      if (tr === null) ok = false;
      else trajectories.push(tr);
    });
    if (task === null || args === null || summary === null || stats === null || !ok) return null;
    return { task, args, summary, stats, trajectories };
  }

  trajectory(x: unknown, p: string, objects: Set<string>, agents: Map<string, Agent>): Trajectory | null {
    const o = this.obj(x, p);
    if (o === null) return null;
    const agentName = this.str(this.field(o, 'agent', p), `${p}.agent`);
    const agent = agentName === null ? undefined : agents.get(agentName);
    if (agentName !== null && agent === undefined) {
      return this.fail(`${p}.agent`, `unknown agent "${agentName}" (not declared in scene.agents)`);
    }
    const label = o['label'] === undefined || o['label'] === null ? '' : this.str(o['label'], `${p}.label`);
    const holding = o['holding'] === undefined || o['holding'] === null ? null : this.str(o['holding'], `${p}.holding`);
    if (holding !== null && !objects.has(holding)) return this.fail(`${p}.holding`, `unknown object "${holding}" (not declared in scene.objects)`);
    const fs = this.arr(this.field(o, 'frames', p), `${p}.frames`);
    if (fs === null || agent === undefined || label === null) return null;
    if (fs.length === 0) return this.fail(`${p}.frames`, 'expected at least one frame');
    const links = new Set(agent.links.map((l) => l.name));
    const frames: Frame[] = [];
    for (let f = 0; f < fs.length; f++) {
      const fp = `${p}.frames[${f}]`;
      const fo = this.obj(fs[f], fp);
      if (fo === null) return null;
      const lp = this.linkPoses(this.field(fo, 'link_poses', fp), `${fp}.link_poses`, links);
      const hp = fo['held_pose'] === undefined || fo['held_pose'] === null ? null : this.pose(fo['held_pose'], `${fp}.held_pose`);
      if (lp === null) return null;
      if (holding !== null && hp === null) return this.fail(`${fp}.held_pose`, `missing: the trajectory holds "${holding}"`);
      let t: number | null = null;
      if (fo['t'] !== undefined && fo['t'] !== null) {
        if (typeof fo['t'] !== 'number' || !Number.isFinite(fo['t']) || fo['t'] < 0) return this.fail(`${fp}.t`, 'expected a finite number of seconds >= 0');
        t = fo['t'];
      }
      frames.push({ link_poses: lp, held_pose: hp, t });
    }
    return { agent: agent.name, label, holding, frames };
  }

  tree(x: unknown, steps: Step[] | null): TreeNode[] | null {
    const a = this.arr(x, 'tree');
    if (a === null) return null;
    const nodes: TreeNode[] = [];
    const ids = new Set<number>();
    a.forEach((item, i) => {
      const p = `tree[${i}]`;
      const o = this.obj(item, p);
      if (o === null) return;
      const id = this.int(this.field(o, 'id', p), `${p}.id`);
      if (id === null) return;
      if (ids.has(id)) this.fail(`${p}.id`, `id ${id} appears twice`);
      ids.add(id);
      const task = o['task'] === undefined || o['task'] === null ? null : this.str(o['task'], `${p}.task`);
      const action = o['action'] === undefined || o['action'] === null ? null : this.str(o['action'], `${p}.action`);
      if ((task === null) === (action === null)) this.fail(p, 'expected exactly one of "task" (a compound task) or "action" (a primitive one)');
      const args = this.strs(o['args'] ?? [], `${p}.args`) ?? [];
      const method = o['method'] === undefined || o['method'] === null ? null : this.str(o['method'], `${p}.method`);
      const children: number[] = [];
      (this.arr(o['children'] ?? [], `${p}.children`) ?? []).forEach((c, k) => {
        const cid = this.int(c, `${p}.children[${k}]`);
        if (cid !== null) children.push(cid);
      });
      const step = o['step'] === undefined || o['step'] === null ? null : this.int(o['step'], `${p}.step`);
      if (step !== null && steps !== null) {
        const s = steps[step];
        if (s === undefined) this.fail(`${p}.step`, `step ${step} does not exist (the plan has ${steps.length} steps)`);
        else if (s.id !== id) this.fail(`${p}.step`, `step ${step} has id ${s.id}, this entry has id ${id}`);
      }
      nodes.push({ id, task, action, args, method, children, step });
    });
    nodes.forEach((n, i) => {
      n.children.forEach((c, k) => {
        if (!ids.has(c)) this.fail(`tree[${i}].children[${k}]`, `id ${c} is not in tree`);
      });
    });
    return nodes;
  }
}

function kindOf(x: unknown): string {
  if (x === null) return 'null';
  if (x === undefined) return 'nothing';
  if (Array.isArray(x)) return 'an array';
  if (typeof x === 'object') return 'an object';
  if (typeof x === 'string') return `the string ${JSON.stringify(x.length > 40 ? `${x.slice(0, 40)}…` : x)}`;
  return `${typeof x} ${String(x)}`;
}
