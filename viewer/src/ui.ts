// The page's panels: title, decomposition tree, current step (GTP summary, shared literals),
// step list, timeline controls and the error panel. Pure DOM; the 3D view lives in main.ts.

import type { Literal, Plan, Step, TreeNode } from './plan';
import type { Timeline, WorldState } from './timeline';

function el<K extends keyof HTMLElementTagNameMap>(tag: K, cls?: string, text?: string): HTMLElementTagNameMap[K] {
  const e = document.createElement(tag);
  if (cls !== undefined) e.className = cls;
  if (text !== undefined) e.textContent = text;
  return e;
}

function byId<T extends HTMLElement = HTMLElement>(id: string): T {
  const e = document.getElementById(id);
  if (e === null) throw new Error(`the page lacks #${id}`);
  return e as T;
}

const PLAY_ICON = '<svg viewBox="0 0 16 16" width="14" height="14" aria-hidden="true"><path d="M3 2v12l11-6z" fill="currentColor"/></svg>';
const PAUSE_ICON = '<svg viewBox="0 0 16 16" width="14" height="14" aria-hidden="true"><path d="M3 2h4v12H3zM9 2h4v12H9z" fill="currentColor"/></svg>';

export const call = (name: string, args: string[]): string => `${name}(${args.join(', ')})`;
const literal = (l: Literal): string => `(${l.join(' ')})`;

export interface UiHandlers {
  seekStep(i: number): void;
  seekFraction(f: number): void;
  togglePlay(): void;
  step(delta: number): void;
  speed(s: number): void;
  camera(mode: string): void;
  openFile(file: File): void;
}

export class Ui {
  private treeNodes = new Map<number, HTMLElement>();
  private stepItems: HTMLElement[] = [];
  /** For each step, the tree ids of its action and of every task above it. */
  private stepPaths: number[][] = [];
  private plan: Plan | null = null;
  private shownStep = -2;
  private shownTrajectory: unknown = undefined;
  private scrubbing = false;

  readonly title = byId('title');
  readonly tree = byId('tree');
  readonly steps = byId<HTMLOListElement>('steps');
  readonly stepNumber = byId('step-number');
  readonly stepAction = byId('step-action');
  readonly stepGtp = byId('step-gtp');
  readonly literals = byId('literals');
  readonly planStats = byId('plan-stats');
  readonly scrubber = byId<HTMLInputElement>('scrubber');
  readonly ticks = byId('ticks');
  readonly clock = byId('clock');
  readonly playButton = byId<HTMLButtonElement>('play');
  readonly cameraSelect = byId<HTMLSelectElement>('camera-select');
  readonly errorPanel = byId('error-panel');
  readonly banner = byId('status-banner');

  constructor(h: UiHandlers) {
    this.scrubber.addEventListener('input', () => {
      this.scrubbing = true;
      h.seekFraction(Number(this.scrubber.value) / Number(this.scrubber.max));
    });
    this.scrubber.addEventListener('change', () => (this.scrubbing = false));
    this.playButton.innerHTML = PLAY_ICON;
    this.playButton.addEventListener('click', () => h.togglePlay());
    byId('prev').addEventListener('click', () => h.step(-1));
    byId('next').addEventListener('click', () => h.step(1));
    byId<HTMLSelectElement>('speed').addEventListener('change', (e) => h.speed(Number((e.target as HTMLSelectElement).value)));
    this.cameraSelect.addEventListener('change', () => h.camera(this.cameraSelect.value));
    const input = byId<HTMLInputElement>('file-input');
    input.addEventListener('change', () => {
      const f = input.files?.[0];
      if (f !== undefined) h.openFile(f);
      input.value = '';
    });
    const overlay = byId('drop-overlay');
    window.addEventListener('dragover', (e) => {
      e.preventDefault();
      overlay.hidden = false;
    });
    window.addEventListener('dragleave', (e) => {
      if (e.relatedTarget === null) overlay.hidden = true;
    });
    window.addEventListener('drop', (e) => {
      e.preventDefault();
      overlay.hidden = true;
      const f = e.dataTransfer?.files[0];
      if (f !== undefined) h.openFile(f);
    });
    window.addEventListener('keydown', (e) => {
      if (e.target instanceof HTMLInputElement || e.target instanceof HTMLSelectElement) return;
      if (e.key === ' ') {
        e.preventDefault();
        h.togglePlay();
      } else if (e.key === 'ArrowLeft') h.step(-1);
      else if (e.key === 'ArrowRight') h.step(1);
    });
    this.handlers = h;
  }

  private readonly handlers: UiHandlers;

  setPlan(plan: Plan, timeline: Timeline, source: string): void {
    this.plan = plan;
    this.shownStep = -2;
    this.title.replaceChildren(
      el('span', '', `${plan.domain} / ${plan.problem}`),
      el('span', 'muted', ' · '),
      el('span', `status-${plan.status}`, plan.status),
      el('span', 'muted', ` · ${plan.steps.length} steps · ${source}`),
    );
    this.banner.hidden = plan.status === 'solved';
    this.banner.textContent = plan.status === 'solved' ? '' : `no plan (${plan.status})${plan.message ? `: ${plan.message}` : ''}`;

    // Decomposition tree, from the roots; parents recorded to find a step's ancestors.
    const byId = new Map(plan.tree.map((n) => [n.id, n]));
    const parent = new Map<number, number>();
    for (const n of plan.tree) for (const c of n.children) parent.set(c, n.id);
    this.treeNodes.clear();
    const seen = new Set<number>();
    const render = (ids: number[]): HTMLUListElement => {
      const ul = el('ul');
      for (const id of ids) {
        const n = byId.get(id);
        if (n === undefined || seen.has(id)) continue; // the validator reports unknown ids; cycles are cut
        seen.add(id);
        const li = el('li');
        li.append(this.treeNode(n, plan.steps));
        if (n.children.length > 0) li.append(render(n.children));
        ul.append(li);
      }
      return ul;
    };
    this.tree.replaceChildren(render(plan.root));
    if (plan.root.length === 0) this.tree.append(el('div', 'literals none', 'no decomposition'));
    this.stepPaths = plan.steps.map((s) => {
      const path = [s.id];
      let p = parent.get(s.id);
      const guard = new Set<number>();
      while (p !== undefined && !guard.has(p)) {
        guard.add(p);
        path.push(p);
        p = parent.get(p);
      }
      return path;
    });

    // Step list.
    this.stepItems = plan.steps.map((s, i) => {
      const li = el('li', '', call(s.action, s.args));
      li.dataset['step'] = String(i);
      li.title = s.gtp ? `geometric task ${call(s.gtp.task, s.gtp.args)}` : 'symbolic action';
      li.addEventListener('click', () => this.handlers.seekStep(i));
      return li;
    });
    this.steps.replaceChildren(...this.stepItems);
    if (plan.steps.length === 0) this.steps.append(el('li', 'literals none', 'no steps'));

    // Ticks at step starts on the scrubber.
    this.ticks.replaceChildren(
      ...timeline.spans.map((span, i) => {
        const t = el('span', plan.steps[i]!.gtp ? 'gs' : '');
        t.style.left = `${timeline.duration > 0 ? (100 * span.start) / timeline.duration : 0}%`;
        return t;
      }),
    );

    const st = plan.stats;
    // Scalars only: nested tables (per-GTP-task figures) are shown per step.
    const parts = Object.entries(st)
      .filter(([, v]) => typeof v !== 'object' || v === null)
      .map(([k, v]) => `${k.replace(/_/g, ' ')} ${typeof v === 'number' ? +v.toFixed(3) : String(v)}`);
    this.planStats.textContent = parts.length > 0 ? `search: ${parts.join(' · ')}` : '';
  }

  private treeNode(n: TreeNode, steps: Step[]): HTMLElement {
    if (n.action !== null) {
      const d = el('span', 'node action');
      d.append(el('span', 'stepno', n.step === null ? '·' : String(n.step)), el('span', 'txt', call(n.action, n.args)));
      if (n.step !== null && steps[n.step]?.gtp) d.append(el('span', 'badge'));
      d.title = call(n.action, n.args);
      if (n.step !== null) {
        const i = n.step;
        d.addEventListener('click', () => this.handlers.seekStep(i));
      }
      this.treeNodes.set(n.id, d);
      return d;
    }
    const d = el('span', 'node task');
    d.append(el('span', 'txt', call(n.task ?? '?', n.args)));
    if (n.method !== null) d.append(el('span', 'method', n.method));
    d.title = `${call(n.task ?? '?', n.args)}${n.method !== null ? ` by method ${n.method}` : ''}`;
    this.treeNodes.set(n.id, d);
    return d;
  }

  /** Shows time `t` of `duration`: current step highlighted everywhere, its changes listed. */
  update(state: WorldState, t: number, duration: number, playing: boolean): void {
    const plan = this.plan;
    if (plan === null) return;
    if (!this.scrubbing) this.scrubber.value = String(Math.round((duration > 0 ? t / duration : 0) * Number(this.scrubber.max)));
    this.clock.textContent = `${t.toFixed(1)} / ${duration.toFixed(1)} s`;
    if (this.playButton.dataset['playing'] !== String(playing)) {
      this.playButton.dataset['playing'] = String(playing);
      this.playButton.innerHTML = playing ? PAUSE_ICON : PLAY_ICON;
      this.playButton.setAttribute('aria-label', playing ? 'pause' : 'play');
    }
    const k = state.step;
    if (k !== this.shownStep) {
      this.shownStep = k;
      this.shownTrajectory = undefined;
      this.stepItems.forEach((li, i) => {
        li.classList.toggle('current', i === k);
        li.classList.toggle('done', i < k);
      });
      const path = new Set(k >= 0 ? this.stepPaths[k] : []);
      const current = k >= 0 ? plan.steps[k]!.id : undefined;
      for (const [id, node] of this.treeNodes) {
        node.classList.toggle('current', id === current);
        node.classList.toggle('ancestor', id !== current && path.has(id));
      }
      for (const n of plan.tree) {
        const node = this.treeNodes.get(n.id);
        if (node !== undefined && n.step !== null) node.classList.toggle('done', n.step < k);
      }
      if (current !== undefined) this.treeNodes.get(current)?.scrollIntoView({ block: 'nearest' });
      this.stepItems[k]?.scrollIntoView({ block: 'nearest' });
      this.showStep(k >= 0 ? plan.steps[k]! : null);
    }
    if (state.trajectory !== this.shownTrajectory) {
      this.shownTrajectory = state.trajectory;
      for (const s of this.stepGtp.querySelectorAll<HTMLElement>('[data-traj]')) {
        s.classList.toggle('traj', state.trajectory !== null && s.dataset['traj'] === String(state.trajectory.index));
      }
    }
  }

  private showStep(s: Step | null): void {
    this.stepNumber.textContent = s === null ? '–' : `${s.index + 1} of ${this.plan?.steps.length ?? 0}`;
    this.stepAction.textContent = s === null ? 'no steps' : call(s.action, s.args);
    this.stepGtp.replaceChildren();
    if (s !== null && s.gtp !== null) {
      const g = s.gtp;
      const table = el('table');
      const row = (k: string, v: Node | string): void => {
        const tr = el('tr');
        const td = el('td');
        td.append(v);
        tr.append(el('td', '', k), td);
        table.append(tr);
      };
      row('geometric task', call(g.task, g.args));
      const trajs = el('span');
      g.trajectories.forEach((tr, i) => {
        if (i > 0) trajs.append(' → ');
        const sp = el('span', '', `${tr.label || 'trajectory'}${tr.holding ? ` [${tr.holding}]` : ''}`);
        sp.dataset['traj'] = String(i);
        trajs.append(sp);
      });
      row('trajectories', trajs);
      for (const [k, v] of Object.entries(g.summary)) {
        if (v !== null && v !== undefined) row(k.replace(/_/g, ' '), typeof v === 'number' ? String(+v.toFixed(3)) : String(v));
      }
      const stats = Object.entries(g.stats).map(([k, v]) => `${k.replace(/_/g, ' ')} ${typeof v === 'number' ? +v.toFixed(2) : String(v)}`);
      if (stats.length > 0) row('GTP stats', stats.join(', '));
      this.stepGtp.append(table);
    } else if (s !== null) {
      this.stepGtp.append(el('span', '', 'symbolic action (no geometric task)'));
    }
    this.literals.replaceChildren();
    if (s === null) return;
    for (const l of s.added) this.literals.append(el('li', 'added', `+ ${literal(l)}`));
    for (const l of s.deleted) this.literals.append(el('li', 'deleted', `− ${literal(l)}`));
    if (s.added.length === 0 && s.deleted.length === 0) this.literals.append(el('li', 'none', 'no literal added or deleted'));
  }

  setCameraModes(modes: { value: string; label: string }[], current: string): void {
    this.cameraSelect.replaceChildren(
      ...modes.map((m) => {
        const o = el('option', '', m.label);
        o.value = m.value;
        return o;
      }),
    );
    this.cameraSelect.value = current;
  }

  showError(source: string, problems: string[]): void {
    byId('error-source').textContent = source;
    byId('error-list').replaceChildren(...problems.map((p) => el('li', '', p)));
    this.errorPanel.hidden = false;
  }

  clearError(): void {
    this.errorPanel.hidden = true;
  }

  clearPlan(): void {
    this.plan = null;
    this.title.textContent = 'no plan loaded';
    this.tree.replaceChildren();
    this.steps.replaceChildren();
    this.ticks.replaceChildren();
    this.literals.replaceChildren();
    this.stepGtp.replaceChildren();
    this.stepAction.textContent = '–';
    this.stepNumber.textContent = '–';
    this.planStats.textContent = '';
    this.banner.hidden = true;
    this.treeNodes.clear();
    this.stepItems = [];
  }
}
