// The viewer on a plan with the real PR2 of ../shared/robots (ROS's description: COLLADA and STL
// visual meshes), served by `htngtp view`: the page loads every link's visual meshes without an
// error. Skipped without ../shared/robots beside the checkout or without a built htngtp
// (HTNGTP_BIN, set by test.sh). HTNGTP_PR2_PLAN names a plan JSON to use instead of planning one.
import { after, before, describe, test } from 'node:test';
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { existsSync, mkdirSync, mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, resolve } from 'node:path';
import { VIEWER, launch, open, view } from './harness.mjs';

const REPO = resolve(VIEWER, '..');
const ROBOTS = resolve(REPO, '..', 'shared', 'robots');
const BIN = process.env.HTNGTP_BIN;
const skip = !existsSync(join(ROBOTS, 'pr2_description'))
  ? `no ${ROBOTS}/pr2_description (the real robots are not beside this checkout)`
  : !BIN
    ? 'set HTNGTP_BIN to a built htngtp binary to run these'
    : false;

describe('the real PR2', { skip }, () => {
  let dir;
  let planFile;
  let plan;
  let browser;
  let server;
  before(async () => {
    dir = mkdtempSync(join(tmpdir(), 'htngtp-viewer-pr2-'));
    planFile = process.env.HTNGTP_PR2_PLAN;
    if (!planFile) {
      planFile = join(dir, 'plan.json');
      const lib = join(REPO, 'domains', 'library');
      const r = spawnSync(BIN, [
        'plan', join(lib, 'domain-compound.hddl'), join(lib, 'lend-and-debit.hddl'),
        '--scene', join(lib, 'scene-real-pr2.toml'), '--json-out', planFile,
      ], { encoding: 'utf8', timeout: 600_000 });
      assert.equal(r.status, 0, `htngtp plan failed (exit ${r.status}):\n${r.stderr}`);
    }
    plan = JSON.parse(readFileSync(planFile, 'utf8'));
    browser = await launch();
    server = await view(BIN, planFile);
  });
  after(async () => {
    server?.child.kill();
    await browser?.close();
    if (dir) rmSync(dir, { recursive: true, force: true });
  });

  test('the plan lists visual meshes served at mesh/N.EXT', () => {
    const pr2 = plan.scene.agents.find((a) => a.kind === 'robot');
    const visuals = pr2.links.flatMap((l) => l.visuals ?? []);
    assert.ok(visuals.length >= 30, `only ${visuals.length} visuals`);
    for (const v of visuals) {
      assert.match(v.uri, /^mesh\/\d+\.(dae|stl|obj)$/);
      assert.ok(existsSync(v.file), v.file);
    }
    assert.ok(visuals.some((v) => v.uri.endsWith('.dae')), 'no COLLADA visual');
  });

  test('the page draws the links by their visual meshes without errors', async () => {
    const missing = [];
    const watch = (p) => p.on('response', (r) => {
      if (r.status() >= 400) missing.push(`${r.status()} ${r.url()}`);
    });
    browser.context.on('page', watch);
    const page = await open(browser.context, server.url);
    browser.context.off('page', watch);
    try {
      await page.waitForFunction(() => __htngtp.ready && __htngtp.visuals.pending === 0, null, { timeout: 120_000 });
      const h = await page.evaluate(() => ({ error: __htngtp.error, visuals: __htngtp.visuals, steps: __htngtp.stepCount }));
      assert.equal(h.error, null);
      assert.equal(h.steps, plan.steps.length);
      const withVisuals = plan.scene.agents.flatMap((a) => a.links).filter((l) => (l.visuals ?? []).length > 0).length;
      assert.deepEqual(h.visuals.failed, []);
      assert.equal(h.visuals.links, withVisuals);
      assert.ok(h.visuals.meshes >= withVisuals, `${h.visuals.meshes} meshes for ${withVisuals} links`);
      // No request failed but the browser's own favicon.ico, and the page logged no error.
      assert.deepEqual(missing.filter((m) => !m.endsWith('/favicon.ico')), []);
      const errors = page.logs.filter((l) => l.startsWith('pageerror') || (l.startsWith('error') && !l.includes('Failed to load resource')));
      assert.deepEqual(errors, []);
      const px = await page.evaluate(() => __htngtp.pixelStats());
      assert.ok(px.variance > 200, `luminance variance ${px.variance}`);
      // A picture for a person to look at (under target/, as the other tests' screenshot).
      mkdirSync(join(REPO, 'target'), { recursive: true });
      await page.screenshot({ path: join(REPO, 'target', 'viewer-real-pr2.png') });
      // A mesh file the plan does not name is not served.
      const r = await fetch(new URL('mesh/9999.dae', server.url));
      assert.equal(r.status, 404);
    } finally {
      await page.close();
    }
  });
});
