// Test harness: a static file server on 127.0.0.1 for the built viewer, and a headless Debian
// Chromium driven by playwright-core with software WebGL (SwiftShader). No network is used.
import { spawn } from 'node:child_process';
import { createServer } from 'node:http';
import { mkdtempSync, readFileSync, rmSync, existsSync, statSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { extname, join, normalize, resolve, sep } from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';

export const VIEWER = resolve(fileURLToPath(new URL('..', import.meta.url)));
export const DIST = join(VIEWER, 'dist');
export const CHROMIUM = process.env.CHROMIUM ?? '/usr/bin/chromium';

const TYPES = {
  '.html': 'text/html; charset=utf-8', '.js': 'text/javascript', '.css': 'text/css',
  '.json': 'application/json', '.png': 'image/png', '.svg': 'image/svg+xml',
};

/**
 * Serves DIST, plus extra in-memory documents (`extra`: URL path -> string). Resolves to
 * { url, close }.
 */
export function serve(extra = {}) {
  const server = createServer((req, res) => {
    const path = decodeURIComponent(new URL(req.url, 'http://x').pathname);
    if (Object.hasOwn(extra, path)) {
      res.writeHead(200, { 'content-type': 'application/json', 'cache-control': 'no-store' });
      res.end(extra[path]);
      return;
    }
    const file = normalize(join(DIST, path === '/' ? 'index.html' : path));
    if (!file.startsWith(DIST + sep) || !existsSync(file) || !statSync(file).isFile()) {
      res.writeHead(404, { 'content-type': 'text/plain' });
      res.end('not found');
      return;
    }
    res.writeHead(200, { 'content-type': TYPES[extname(file)] ?? 'application/octet-stream' });
    res.end(readFileSync(file));
  });
  return new Promise((ok) => {
    server.listen(0, '127.0.0.1', () => {
      const { port } = server.address();
      ok({ url: `http://127.0.0.1:${port}/`, close: () => new Promise((done) => server.close(done)) });
    });
  });
}

/** Headless Chromium with software WebGL; the network stays closed (no background requests). */
export async function launch() {
  const profile = mkdtempSync(join(tmpdir(), 'htngtp-viewer-chromium-'));
  const context = await chromium.launchPersistentContext(profile, {
    executablePath: CHROMIUM,
    headless: true,
    viewport: { width: 1400, height: 860 },
    args: [
      '--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
      '--disable-background-networking', '--disable-component-update', '--disable-sync',
      '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist',
    ],
  });
  return {
    context,
    close: async () => {
      await context.close();
      rmSync(profile, { recursive: true, force: true });
    },
  };
}

/** Opens the viewer at `url` and waits until it has shown a plan or an error. */
export async function open(context, url) {
  const page = await context.newPage();
  const logs = [];
  page.on('console', (m) => logs.push(`${m.type()}: ${m.text()}`));
  page.on('pageerror', (e) => logs.push(`pageerror: ${e.message}`));
  await page.goto(url);
  await page.waitForFunction(() => window.__htngtp && (window.__htngtp.ready || window.__htngtp.error), null, { timeout: 30_000 })
    .catch((e) => { throw new Error(`${e.message}\npage log:\n${logs.join('\n')}`); });
  page.logs = logs;
  return page;
}

/** Starts `BIN view PLAN` on a free port; resolves to { url, child } once it prints its URL. */
export function view(bin, plan) {
  const child = spawn(bin, ['view', plan, '--port', '0', '--dist', DIST], { stdio: ['ignore', 'pipe', 'pipe'] });
  return new Promise((ok, fail) => {
    let out = '';
    const timer = setTimeout(() => {
      child.kill();
      fail(new Error(`no URL printed within 10 s: ${out}`));
    }, 10_000);
    child.stdout.on('data', (d) => {
      out += d;
      const m = /http:\/\/127\.0\.0\.1:\d+\//.exec(out);
      if (m) {
        clearTimeout(timer);
        ok({ url: m[0], child });
      }
    });
    child.on('exit', (code) => fail(new Error(`htngtp view exited with ${code}: ${out}`)));
  });
}
