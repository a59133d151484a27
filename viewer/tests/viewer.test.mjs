// Browser tests of the viewer: the built page (dist/) in headless Chromium with software WebGL.
// The plan under test is fixtures/sample-plan.json, or the file named by HTNGTP_PLAN (for example
// the output of `htngtp demo --json`). Run with ./test.sh (builds first).
import { after, before, describe, test } from 'node:test';
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { mkdirSync, readFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { VIEWER, launch, open, serve, view } from './harness.mjs';

const PLAN_FILE = process.env.HTNGTP_PLAN ?? join(VIEWER, 'fixtures', 'sample-plan.json');
const PLAN_TEXT = readFileSync(PLAN_FILE, 'utf8');
const PLAN = JSON.parse(PLAN_TEXT);
// The picture the tests take goes under target/ (tests leave the checkout as it was);
// HTNGTP_SCREENSHOT=viewer/screenshot.png refreshes the README's picture.
const SCREENSHOT = process.env.HTNGTP_SCREENSHOT ?? join(VIEWER, '..', 'target', 'viewer-screenshot.png');

/** A copy of the plan with `edit` applied, as JSON text. */
function variant(edit) {
  const p = structuredClone(PLAN);
  edit(p);
  return JSON.stringify(p);
}

const firstGtpStep = PLAN.steps.findIndex((s) => s.gtp && s.gtp.trajectories.length > 0);
const somePose = { t: [0, 0, 0], q: [0, 0, 0, 1] };

// Bad documents, each with what the error panel must say.
const BAD = {
  '/bad/truncated.json': { text: PLAN_TEXT.slice(0, Math.floor(PLAN_TEXT.length / 2)), says: ['not valid JSON', 'column'] },
  '/bad/empty.json': { text: '', says: ['not valid JSON'] },
  '/bad/not-a-plan.json': { text: '{"hello": "world"}', says: ['format', 'not an htngtp plan JSON'] },
  '/bad/version.json': { text: variant((p) => (p.version = 99)), says: ['version', 'reads version 1, found 99'] },
  '/bad/unknown-object.json': {
    text: variant((p) => (p.steps[p.steps.length - 1].object_poses['blue-book'] = somePose)),
    says: [`steps[${PLAN.steps.length - 1}].object_poses.blue-book`, 'unknown object "blue-book"'],
  },
  '/bad/tree-step.json': {
    text: variant((p) => (p.tree.find((n) => n.step !== undefined && n.step !== null).step = 999)),
    says: ['step 999 does not exist'],
  },
};

// An object described by one shape (not by parts) loses it.
const simple = PLAN.scene.objects.findIndex((o) => o.shape && !o.parts);
if (simple >= 0) {
  BAD['/bad/missing-field.json'] = {
    text: variant((p) => delete p.scene.objects[simple].shape),
    says: [`scene.objects[${simple}].shape: missing`],
  };
}

if (firstGtpStep >= 0) {
  BAD['/bad/unknown-link.json'] = {
    text: variant((p) => {
      const f = p.steps[firstGtpStep].gtp.trajectories[0].frames[0];
      f.link_poses['tail_link'] = somePose;
    }),
    says: [`steps[${firstGtpStep}].gtp.trajectories[0].frames[0].link_poses.tail_link`, 'unknown link "tail_link"'],
  };
}

const compound = PLAN.scene.objects.findIndex((o) => Array.isArray(o.parts) && o.parts.length > 0);
if (compound >= 0) {
  BAD['/bad/part-shape.json'] = {
    text: variant((p) => (p.scene.objects[compound].parts[0].shape = { sphere: { radius: 1 } })),
    says: [`scene.objects[${compound}].parts[0].shape`, 'unknown shape "sphere"'],
  };
}

// A run that found no plan: the scene is still shown, with the reason.
const UNSOLVED = variant((p) => {
  p.status = 'unsolvable';
  p.message = 'no method of lend(member) applies';
  p.steps = [];
  p.tree = [];
  p.root = [];
});

// Visual meshes: the first agent's first link drawn by an ASCII STL box the server holds, and
// the same plan with a mesh the server does not have (the link keeps its collision shapes).
const BOX_STL = ['solid box', ...[[0, 1, 2], [0, 2, 3]].map((t) => [
  'facet normal 0 0 1', 'outer loop', ...t.map((k) => `vertex ${[[0, 0, 0], [0.2, 0, 0], [0.2, 0.2, 0], [0, 0.2, 0]][k].join(' ')}`), 'endloop', 'endfacet',
].join('\n')), 'endsolid box', ''].join('\n');
const withVisual = (uri) => variant((p) => {
  p.scene.agents[0].links[0].visuals = [{ uri, pose: { t: [0, 0, 0.1], q: [0, 0, 0, 1] }, scale: [1, 1, 2], color: [0.9, 0.1, 0.1] }];
});

const extra = {
  '/plan.json': PLAN_TEXT, '/unsolved.json': UNSOLVED,
  '/visual/plan.json': withVisual('mesh/0.stl'), '/visual/mesh/0.stl': BOX_STL,
  '/visual/missing.json': withVisual('mesh/9.stl'),
};
for (const [path, { text }] of Object.entries(BAD)) extra[path] = text;

let server;
let browser;
before(async () => {
  server = await serve(extra);
  browser = await launch();
});
after(async () => {
  await browser?.close();
  await server?.close();
});

const hook = (page, fn, arg) => page.evaluate(fn, arg);

function assertPose(actual, expected, what, tol = 1e-4) {
  assert.ok(actual, `${what}: no pose`);
  for (let i = 0; i < 3; i++) {
    assert.ok(Math.abs(actual.t[i] - expected.t[i]) <= tol, `${what}: t = ${actual.t}, expected ${expected.t}`);
  }
  const n = Math.hypot(...expected.q);
  const dot = actual.q.reduce((s, c, i) => s + c * (expected.q[i] / n), 0);
  assert.ok(Math.abs(Math.abs(dot) - 1) <= tol, `${what}: q = ${actual.q}, expected ${expected.q}`);
}

/** Every object and link of `want` at its pose in the page's snapshot, and nothing extra. */
function assertWorld(snap, want, when) {
  assert.deepEqual(Object.keys(snap.objects).sort(), [...want.objects.keys()].sort(), `${when}: objects`);
  for (const [name, pose] of want.objects) assertPose(snap.objects[name], pose, `${when}: ${name}`);
  for (const [agent, poses] of want.links) {
    assert.deepEqual(Object.keys(snap.links[agent]).sort(), Object.keys(poses).sort(), `${when}: links of ${agent}`);
    for (const [link, pose] of Object.entries(poses)) assertPose(snap.links[agent][link], pose, `${when}: ${agent}/${link}`);
  }
}

/** The poses the JSON says hold after step `i` (i = -1: the scene's): trajectories' last frames, then object_poses. */
function expectedAfter(i) {
  const objects = new Map(PLAN.scene.objects.map((o) => [o.name, o.pose]));
  const links = new Map(PLAN.scene.agents.map((a) => [a.name, { ...a.link_poses }]));
  for (const s of PLAN.steps.slice(0, i + 1)) {
    for (const tr of s.gtp?.trajectories ?? []) {
      Object.assign(links.get(tr.agent), tr.frames.at(-1).link_poses);
      if (tr.holding) objects.set(tr.holding, tr.frames.at(-1).held_pose);
    }
    for (const [k, v] of Object.entries(s.object_poses ?? {})) objects.set(k, v);
  }
  return { objects, links };
}

describe('the sample plan', () => {
  let page;
  before(async () => {
    page = await open(browser.context, server.url);
  });
  after(async () => page?.close());

  test('loads without error and builds one 3D object per declared object, agent and link', async () => {
    const h = await hook(page, () => ({
      ready: __htngtp.ready, error: __htngtp.error, objects: __htngtp.objectCount,
      agents: __htngtp.agentCount, links: __htngtp.linkCount, steps: __htngtp.stepCount,
    }));
    assert.equal(h.error, null);
    assert.equal(h.ready, true);
    assert.equal(h.objects, PLAN.scene.objects.length);
    assert.equal(h.agents, PLAN.scene.agents.length);
    assert.equal(h.links, PLAN.scene.agents.reduce((n, a) => n + a.links.length, 0));
    assert.equal(h.steps, PLAN.steps.length);
    assert.equal(await page.isVisible('#error-panel'), false);
  });

  test('renders a shaded scene: the canvas is far from uniform', async () => {
    const px = await hook(page, () => __htngtp.pixelStats());
    assert.ok(px.width > 200 && px.height > 200, `canvas ${px.width}x${px.height}`);
    // A blank or single-colour canvas has variance ~0; the lit scene has thousands.
    assert.ok(px.variance > 200, `luminance variance ${px.variance}`);
    assert.ok(px.nonBackground > 0.2, `only ${px.nonBackground} of the pixels show something`);
  });

  test('places objects and links at the scene poses before the first step', async () => {
    const snap = await hook(page, () => {
      __htngtp.seekTime(0);
      return __htngtp.snapshot();
    });
    assertWorld(snap, expectedAfter(-1), 'at the start');
    // objectPose and linkPose agree with the snapshot.
    const o = PLAN.scene.objects[0];
    assertPose(await hook(page, (n) => __htngtp.objectPose(n), o.name), o.pose, o.name);
    const a = PLAN.scene.agents[0];
    const l = a.links[0].name;
    assertPose(await hook(page, ([ag, ln]) => __htngtp.linkPose(ag, ln), [a.name, l]), a.link_poses[l], `${a.name}/${l}`);
  });

  test('lists the steps in plan order and highlights the current one in the list and tree', async () => {
    const items = await page.$$eval('#steps li', (lis) => lis.map((li) => li.textContent));
    assert.deepEqual(items, PLAN.steps.map((s) => `${s.action}(${s.args.join(', ')})`));
    const parent = new Map();
    for (const n of PLAN.tree) for (const c of n.children ?? []) parent.set(c, n);
    for (const i of [0, Math.floor(PLAN.steps.length / 2), PLAN.steps.length - 1]) {
      await page.click(`#steps li[data-step="${i}"]`);
      assert.equal(await hook(page, () => __htngtp.currentStep), i);
      assert.equal(await page.textContent('#steps li.current'), items[i]);
      const s = PLAN.steps[i];
      assert.equal(await page.textContent('#step-action'), `${s.action}(${s.args.join(', ')})`);
      const current = await page.$$eval('#tree .node.current', (ns) => ns.map((n) => n.textContent));
      assert.deepEqual(current, [`${i}${s.action}(${s.args.join(', ')})`]);
      // Every task above the action is marked, and nothing else.
      const ancestors = [];
      for (let p = parent.get(s.id); p; p = parent.get(p.id)) ancestors.push(`${p.task}(${p.args.join(', ')})${p.method ?? ''}`);
      const marked = await page.$$eval('#tree .node.ancestor', (ns) => ns.map((n) => n.textContent));
      assert.deepEqual(new Set(marked), new Set(ancestors));
      // The literals panel lists exactly the step's added and deleted literals.
      const lits = await page.$$eval('#literals li', (ls) => ls.map((l) => `${l.className} ${l.textContent}`));
      const want = [
        ...s.added.map((l) => `added + (${l.join(' ')})`),
        ...s.deleted.map((l) => `deleted − (${l.join(' ')})`),
      ];
      assert.deepEqual(lits, want.length > 0 ? want : ['none no literal added or deleted']);
    }
  });

  test('poses links and the held object from the trajectory frames', async () => {
    // Frames 0, middle and last-but-one of every trajectory (the last one is where the next
    // trajectory starts); all sought and read back in one round trip.
    const picks = [];
    for (const [i, s] of PLAN.steps.entries()) {
      for (const [j, tr] of (s.gtp?.trajectories ?? []).entries()) {
        const frames = new Set([0, Math.floor((tr.frames.length - 1) / 2), tr.frames.length - 2]);
        for (const f of frames) if (f >= 0) picks.push([i, j, f]);
      }
    }
    const snaps = await hook(page, (ps) => ps.map(([i, j, f]) => {
      __htngtp.seekFrame(i, j, f);
      return __htngtp.snapshot();
    }), picks);
    picks.forEach(([i, j, f], k) => {
      const snap = snaps[k];
      const tr = PLAN.steps[i].gtp.trajectories[j];
      const frame = tr.frames[f];
      const where = `step ${i} trajectory ${j} (${tr.label}) frame ${f}`;
      assert.equal(snap.step, i, where);
      for (const [link, pose] of Object.entries(frame.link_poses)) assertPose(snap.links[tr.agent][link], pose, `${where}: ${link}`);
      if (tr.holding) assertPose(snap.objects[tr.holding], frame.held_pose, `${where}: held ${tr.holding}`);
    });
    assert.ok(picks.length > 0 || PLAN.steps.every((s) => !s.gtp), 'no trajectory frame checked');
  });

  test('after each step, objects and links are where the JSON says', async () => {
    const times = await hook(page, () => __htngtp.stepTimes());
    assert.equal(times.length, PLAN.steps.length);
    for (let i = 0; i < PLAN.steps.length; i++) {
      const snap = await hook(page, (t) => {
        __htngtp.seekTime(t);
        return __htngtp.snapshot();
      }, times[i].end);
      assertWorld(snap, expectedAfter(i), `after step ${i}`);
    }
  });

  test("plays each trajectory by its frames' times (time_from_start)", async () => {
    const times = await hook(page, () => __htngtp.stepTimes());
    let timed = 0;
    for (const [i, s] of PLAN.steps.entries()) {
      const trs = s.gtp?.trajectories ?? [];
      if (trs.length === 0 || !trs.every((tr) => tr.frames.every((f) => typeof f.t === 'number'))) continue;
      const want = trs.reduce((d, tr) => d + Math.max(1 / 20, tr.frames.at(-1).t - tr.frames[0].t), 0);
      assert.ok(Math.abs(times[i].end - times[i].start - want) < 1e-6, `step ${i}: lasts ${times[i].end - times[i].start} s, its frames ${want} s`);
      timed++;
    }
    const anyTimed = PLAN.steps.some((s) => (s.gtp?.trajectories ?? []).some((tr) => tr.frames.some((f) => typeof f.t === 'number')));
    assert.ok(timed > 0 || !anyTimed, 'no timed step checked');
  });

  test('plays to the end, step by step, and stops at the final state', async () => {
    await hook(page, () => __htngtp.seekTime(0));
    const duration = await hook(page, () => __htngtp.duration);
    const speed = 10;
    const started = Date.now();
    await hook(page, (s) => __htngtp.play(s), speed);
    const seen = [];
    for (;;) {
      const h = await hook(page, () => ({ playing: __htngtp.playing, step: __htngtp.currentStep, t: __htngtp.time }));
      if (seen.at(-1) !== h.step) seen.push(h.step);
      if (!h.playing) break;
      assert.ok(Date.now() - started < 60_000, 'playback did not finish within 60 s');
      await page.waitForTimeout(20);
    }
    const elapsed = (Date.now() - started) / 1000;
    assert.ok(elapsed >= (duration / speed) * 0.8, `played ${duration} s at ${speed}x in ${elapsed} s: too fast`);
    for (let k = 1; k < seen.length; k++) assert.ok(seen[k] > seen[k - 1], `steps went backwards: ${seen}`);
    assert.equal(seen.at(-1), PLAN.steps.length - 1);
    assert.equal(await hook(page, () => __htngtp.time), duration);
    assert.equal(await page.textContent('#steps li.current'), `${PLAN.steps.at(-1).action}(${PLAN.steps.at(-1).args.join(', ')})`);
    assertWorld(await hook(page, () => __htngtp.snapshot()), expectedAfter(PLAN.steps.length - 1), 'at the end');
  });

  test("switches the camera to each agent's eye link and back to orbit", async () => {
    await hook(page, () => __htngtp.seekTime(0));
    const options = await page.$$eval('#camera-select option', (os) => os.map((o) => o.value));
    const eyes = PLAN.scene.agents.filter((a) => a.eye_link);
    assert.deepEqual(options, ['orbit', ...eyes.map((a) => `eye:${a.name}`)]);
    for (const a of eyes) {
      await page.selectOption('#camera-select', `eye:${a.name}`);
      assert.equal(await hook(page, () => __htngtp.camera), `eye:${a.name}`);
      const cam = await hook(page, () => __htngtp.cameraPose());
      const eye = a.link_poses[a.eye_link];
      for (let i = 0; i < 3; i++) assert.ok(Math.abs(cam.t[i] - eye.t[i]) < 1e-4, `camera at ${cam.t}, ${a.name}'s eye at ${eye.t}`);
      const px = await hook(page, () => __htngtp.pixelStats());
      assert.ok(px.variance > 100, `${a.name}'s view is nearly uniform (variance ${px.variance})`);
    }
    await page.selectOption('#camera-select', 'orbit');
    const cam = await hook(page, () => __htngtp.cameraPose());
    assert.ok(!eyes.some((a) => Math.hypot(...cam.t.map((c, i) => c - a.link_poses[a.eye_link].t[i])) < 1e-3), 'orbit camera still at an eye');
  });

  test('saves a screenshot of a geometric step under way', async () => {
    // The first step that puts a held object down, midway through its trajectories.
    const i = PLAN.steps.findIndex((s) => s.gtp && s.gtp.trajectories.some((t) => t.holding) && s.index > firstGtpStep);
    const k = i >= 0 ? i : Math.max(firstGtpStep, 0);
    const trs = PLAN.steps[k]?.gtp?.trajectories ?? [];
    if (trs.length > 0) {
      const j = Math.min(1, trs.length - 1);
      await hook(page, ([a, b, c]) => __htngtp.seekFrame(a, b, c), [k, j, Math.floor(trs[j].frames.length * 0.6)]);
    }
    await page.waitForTimeout(200);
    mkdirSync(dirname(SCREENSHOT), { recursive: true });
    await page.screenshot({ path: SCREENSHOT });
    assert.equal(await hook(page, () => __htngtp.currentStep), k);
  });
});

describe('visual meshes', () => {
  const settled = (page) => page.waitForFunction(() => __htngtp.ready && __htngtp.visuals.pending === 0, null, { timeout: 30_000 });

  test('a link with a visual mesh is drawn by it, the others by their shapes', async () => {
    const page = await open(browser.context, `${server.url}?plan=/visual/plan.json`);
    try {
      await settled(page);
      const v = await hook(page, () => __htngtp.visuals);
      assert.deepEqual(v, { pending: 0, links: 1, meshes: 1, failed: [] });
      assert.equal(await hook(page, () => __htngtp.linkCount), PLAN.scene.agents.reduce((n, a) => n + a.links.length, 0));
      assert.ok(!page.logs.some((l) => l.startsWith('error') || l.startsWith('pageerror')), page.logs.join('\n'));
    } finally {
      await page.close();
    }
  });

  test('a visual mesh that does not load leaves the link on its collision shapes', async () => {
    const page = await open(browser.context, `${server.url}?plan=/visual/missing.json`);
    try {
      await settled(page);
      const v = await hook(page, () => __htngtp.visuals);
      assert.equal(v.links, 0);
      assert.equal(v.failed.length, 1);
      assert.ok(v.failed[0].includes('HTTP 404'), v.failed[0]);
      assert.equal(await hook(page, () => __htngtp.error), null);
      assert.ok((await hook(page, () => __htngtp.pixelStats())).variance > 200);
    } finally {
      await page.close();
    }
  });
});

describe('bad input shows the error panel', () => {
  for (const [path, { says }] of Object.entries(BAD)) {
    test(`${path.slice('/bad/'.length)}`, async () => {
      const page = await open(browser.context, `${server.url}?plan=${path}`);
      try {
        assert.equal(await page.isVisible('#error-panel'), true, 'the error panel is hidden');
        const text = await page.textContent('#error-panel');
        for (const s of says) assert.ok(text.includes(s), `the error panel lacks "${s}":\n${text}`);
        assert.equal(await hook(page, () => __htngtp.ready), false);
        assert.equal(await hook(page, () => __htngtp.objectCount), 0);
        // Not a blank screen: the header and the panel's help are shown.
        assert.ok((await page.textContent('#topbar')).includes('open plan'));
      } finally {
        await page.close();
      }
    });
  }

  test('a run without a plan shows the scene and why there is no plan', async () => {
    const page = await open(browser.context, `${server.url}?plan=/unsolved.json`);
    try {
      const h = await hook(page, () => ({ ready: __htngtp.ready, error: __htngtp.error, objects: __htngtp.objectCount, steps: __htngtp.stepCount, step: __htngtp.currentStep }));
      assert.deepEqual(h, { ready: true, error: null, objects: PLAN.scene.objects.length, steps: 0, step: -1 });
      assert.equal(await page.isVisible('#error-panel'), false);
      assert.ok((await page.textContent('#status-banner')).includes('no method of lend(member) applies'));
      assert.ok((await hook(page, () => __htngtp.pixelStats())).variance > 200);
      await hook(page, () => __htngtp.play(10)); // nothing to play: must not throw or move
      assert.equal(await hook(page, () => __htngtp.time), 0);
    } finally {
      await page.close();
    }
  });

  test('a missing plan says how to get one; the file picker and drag-and-drop then load plans', async () => {
    const page = await open(browser.context, `${server.url}?plan=nowhere.json`);
    try {
      const text = await page.textContent('#error-panel');
      assert.ok(text.includes('HTTP 404'), text);
      assert.ok(text.includes('htngtp view'), text);
      await page.setInputFiles('#file-input', PLAN_FILE);
      await page.waitForFunction(() => __htngtp.ready, null, { timeout: 10_000 });
      assert.equal(await page.isVisible('#error-panel'), false);
      assert.equal(await hook(page, () => __htngtp.objectCount), PLAN.scene.objects.length);
      // And a bad file after a good one: the error replaces the scene.
      await page.setInputFiles('#file-input', { name: 'broken.json', mimeType: 'application/json', buffer: Buffer.from('{"format": "htngtp-plan", "version": 1,') });
      await page.waitForFunction(() => __htngtp.error !== null, null, { timeout: 10_000 });
      assert.ok((await page.textContent('#error-panel')).includes('broken.json'));
      assert.equal(await hook(page, () => __htngtp.objectCount), 0);
      // Dropping a plan on the page opens it too.
      const dropped = await page.evaluateHandle((text) => {
        const d = new DataTransfer();
        d.items.add(new File([text], 'dropped.json', { type: 'application/json' }));
        return d;
      }, PLAN_TEXT);
      await page.dispatchEvent('#view', 'drop', { dataTransfer: dropped });
      await page.waitForFunction(() => __htngtp.ready, null, { timeout: 10_000 });
      assert.equal(await page.isVisible('#error-panel'), false);
      assert.ok((await page.textContent('#title')).includes('dropped.json'));
    } finally {
      await page.close();
    }
  });
});

// `htngtp view` end to end, when a built binary is named (test.sh passes HTNGTP_BIN through).
const BIN = process.env.HTNGTP_BIN;
describe('htngtp view', { skip: BIN ? false : 'set HTNGTP_BIN to a built htngtp binary to run these' }, () => {
  test('serves the page and the plan on 127.0.0.1 and prints the URL', async () => {
    const { url, child } = await view(BIN, PLAN_FILE);
    try {
      const page = await open(browser.context, url);
      try {
        const h = await hook(page, () => ({ ready: __htngtp.ready, error: __htngtp.error, objects: __htngtp.objectCount, steps: __htngtp.stepCount }));
        assert.deepEqual(h, { ready: true, error: null, objects: PLAN.scene.objects.length, steps: PLAN.steps.length });
      } finally {
        await page.close();
      }
    } finally {
      child.kill();
    }
  });

  test('says how to build the viewer when it is not built', () => {
    const r = spawnSync(BIN, ['view', PLAN_FILE, '--port', '0', '--dist', join(VIEWER, 'no-such-dist')], { encoding: 'utf8' });
    assert.equal(r.status, 3, r.stderr);
    assert.ok(r.stderr.includes('npm --prefix') && r.stderr.includes('run build'), r.stderr);
  });
});
