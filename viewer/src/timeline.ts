// The plan as a function of time: which step is current and where every object and link is.
// Each step lasts as long as its trajectories (played one after the other, each frame at its
// `t`, the timed point's `time_from_start`; older plans without times: frames evenly spaced) or
// a short pause when it moves nothing; between two frames, poses are interpolated (lerp of
// translations, slerp of rotations).

import type { Plan, Pose, Quat, Step, Trajectory, Vec3 } from './plan';

/** Seconds between two consecutive trajectory frames at 1x speed, for frames without times. */
export const FRAME_DT = 1 / 20;
/** How long a step without trajectories (a symbolic action) is shown at 1x speed. */
export const SYMBOLIC_STEP = 0.8;

export interface TrajectorySpan {
  start: number;
  end: number;
  trajectory: Trajectory;
  /** Position of the trajectory within its step. */
  index: number;
  /** Seconds from the trajectory's start at which each frame is shown. */
  times: number[];
}

/** The frames' times: their `t` when every frame has one and they increase, else evenly spaced. */
export function frameTimes(tr: Trajectory): number[] {
  const ts = tr.frames.map((f) => f.t);
  const timed = ts.every((t, i) => t !== null && (i === 0 || t > ts[i - 1]!));
  return timed ? ts.map((t) => t! - ts[0]!) : tr.frames.map((_, i) => i * FRAME_DT);
}

/** Index `f` of the last frame shown at or before `t` (binary search over increasing times). */
function frameBefore(times: number[], t: number): number {
  let lo = 0;
  let hi = times.length - 1;
  while (lo < hi) {
    const mid = (lo + hi + 1) >> 1;
    if (times[mid]! <= t) lo = mid;
    else hi = mid - 1;
  }
  return lo;
}

export interface StepSpan {
  start: number;
  end: number;
  trajectories: TrajectorySpan[];
}

/** Poses of everything at one instant; links keyed by agent then link. */
export interface WorldState {
  objects: Map<string, Pose>;
  links: Map<string, Map<string, Pose>>;
  /** Index of the step under way (or the last one at the end); -1 when the plan has no steps. */
  step: number;
  /** The trajectory under way within the step, or null. */
  trajectory: TrajectorySpan | null;
  /** Objects held by an agent at this instant. */
  held: Set<string>;
}

interface Snapshot {
  objects: Map<string, Pose>;
  links: Map<string, Map<string, Pose>>;
}

export class Timeline {
  readonly spans: StepSpan[] = [];
  readonly duration: number;
  /** The world when each step starts (index i) and after the last one (index steps.length). */
  private readonly snapshots: Snapshot[] = [];

  constructor(private readonly plan: Plan) {
    let t = 0;
    for (const step of plan.steps) {
      const trajectories: TrajectorySpan[] = [];
      const start = t;
      for (const trajectory of step.gtp?.trajectories ?? []) {
        const times = frameTimes(trajectory);
        const d = Math.max(FRAME_DT, times[times.length - 1]!);
        trajectories.push({ start: t, end: t + d, trajectory, index: trajectories.length, times });
        t += d;
      }
      if (trajectories.length === 0) t += SYMBOLIC_STEP;
      this.spans.push({ start, end: t, trajectories });
    }
    this.duration = t;

    let snap: Snapshot = {
      objects: new Map(plan.scene.objects.map((o) => [o.name, o.pose])),
      links: new Map(plan.scene.agents.map((a) => [a.name, new Map(Object.entries(a.link_poses))])),
    };
    this.snapshots.push(snap);
    for (const step of plan.steps) {
      snap = after(snap, step);
      this.snapshots.push(snap);
    }
  }

  /** Index of the step under way at time `t` (the last step at the very end). */
  stepAt(t: number): number {
    const n = this.spans.length;
    if (n === 0) return -1;
    for (let i = 0; i < n; i++) if (t < this.spans[i]!.end) return i;
    return n - 1;
  }

  /** The world at time `t` (clamped to [0, duration]). */
  stateAt(tIn: number): WorldState {
    const t = Math.min(Math.max(tIn, 0), this.duration);
    const k = this.stepAt(t);
    if (k < 0) return { ...copy(this.snapshots[0]!), step: -1, trajectory: null, held: new Set() };
    const span = this.spans[k]!;
    if (t >= span.end) {
      return { ...copy(this.snapshots[k + 1]!), step: k, trajectory: null, held: new Set() };
    }
    const state: WorldState = { ...copy(this.snapshots[k]!), step: k, trajectory: null, held: new Set() };
    for (const ts of span.trajectories) {
      const tr = ts.trajectory;
      const links = state.links.get(tr.agent)!;
      if (t >= ts.end) {
        const last = tr.frames[tr.frames.length - 1]!;
        for (const [name, p] of Object.entries(last.link_poses)) links.set(name, p);
        if (tr.holding !== null && last.held_pose !== null) state.objects.set(tr.holding, last.held_pose);
        continue;
      }
      if (t < ts.start) break;
      const local = t - ts.start;
      const f = frameBefore(ts.times, local);
      const g = Math.min(f + 1, tr.frames.length - 1);
      const a = tr.frames[f]!;
      const b = tr.frames[g]!;
      const gap = ts.times[g]! - ts.times[f]!;
      const s = gap > 0 ? Math.min(1, (local - ts.times[f]!) / gap) : 0;
      for (const [name, p] of Object.entries(a.link_poses)) links.set(name, interpolate(p, b.link_poses[name] ?? p, s));
      if (tr.holding !== null && a.held_pose !== null) {
        state.objects.set(tr.holding, interpolate(a.held_pose, b.held_pose ?? a.held_pose, s));
        state.held.add(tr.holding);
      }
      state.trajectory = ts;
      break;
    }
    return state;
  }

  /** The time at which trajectory `j` of step `i` shows frame `f` exactly. */
  frameTime(i: number, j: number, f: number): number {
    const ts = this.spans[i]?.trajectories[j];
    if (ts === undefined) throw new Error(`step ${i} has no trajectory ${j}`);
    if (f < 0 || f >= ts.trajectory.frames.length) throw new Error(`trajectory ${j} of step ${i} has no frame ${f}`);
    return ts.start + ts.times[f]!;
  }

  /** Poses the plan says hold after step `i` (objects: declared ones carried forward). */
  afterStep(i: number): Snapshot {
    return copy(this.snapshots[i + 1]!);
  }

  get stepCount(): number {
    return this.plan.steps.length;
  }
}

/** The world after a step: its trajectories' last frames, then its `object_poses`. */
function after(before: Snapshot, step: Step): Snapshot {
  const s = copy(before);
  for (const tr of step.gtp?.trajectories ?? []) {
    const last = tr.frames[tr.frames.length - 1]!;
    const links = s.links.get(tr.agent)!;
    for (const [name, p] of Object.entries(last.link_poses)) links.set(name, p);
    if (tr.holding !== null && last.held_pose !== null) s.objects.set(tr.holding, last.held_pose);
  }
  for (const [name, p] of Object.entries(step.object_poses)) s.objects.set(name, p);
  return s;
}

function copy(s: Snapshot): Snapshot {
  return {
    objects: new Map(s.objects),
    links: new Map([...s.links].map(([a, m]) => [a, new Map(m)])),
  };
}

export function interpolate(a: Pose, b: Pose, s: number): Pose {
  if (s <= 0) return a;
  if (s >= 1) return b;
  const t: Vec3 = [a.t[0] + (b.t[0] - a.t[0]) * s, a.t[1] + (b.t[1] - a.t[1]) * s, a.t[2] + (b.t[2] - a.t[2]) * s];
  return { t, q: slerp(a.q, b.q, s) };
}

function slerp(a: Quat, bIn: Quat, s: number): Quat {
  let b = bIn;
  let cos = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
  if (cos < 0) {
    b = [-b[0], -b[1], -b[2], -b[3]];
    cos = -cos;
  }
  let wa: number;
  let wb: number;
  if (cos > 0.9995) {
    wa = 1 - s;
    wb = s;
  } else {
    const theta = Math.acos(cos);
    const sin = Math.sin(theta);
    wa = Math.sin((1 - s) * theta) / sin;
    wb = Math.sin(s * theta) / sin;
  }
  const q: Quat = [wa * a[0] + wb * b[0], wa * a[1] + wb * b[1], wa * a[2] + wb * b[2], wa * a[3] + wb * b[3]];
  const n = Math.hypot(...q);
  return [q[0] / n, q[1] / n, q[2] / n, q[3] / n];
}
