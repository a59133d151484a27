// Bundles the viewer with esbuild into dist/: index.html, assets/viewer.js, assets/viewer.css.
// Everything (three.js included) is bundled: the page needs no network at run time.
//   node build.mjs           build once
//   node build.mjs --serve   rebuild on change and serve dist/ on http://127.0.0.1:5173/
//                            (put a plan.json in dist/, or open ?plan=URL)
import * as esbuild from 'esbuild';
import { copyFileSync, mkdirSync, rmSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const root = dirname(fileURLToPath(import.meta.url));
const dist = join(root, 'dist');
const serve = process.argv.includes('--serve');

const options = {
  entryPoints: { viewer: join(root, 'src', 'main.ts') },
  outdir: join(dist, 'assets'),
  bundle: true,
  format: 'esm',
  target: 'es2022',
  minify: !serve,
  sourcemap: true,
  legalComments: 'linked',
  logLevel: serve ? 'info' : 'warning',
};

if (!serve) rmSync(dist, { recursive: true, force: true });
mkdirSync(join(dist, 'assets'), { recursive: true });
copyFileSync(join(root, 'index.html'), join(dist, 'index.html'));

if (serve) {
  const ctx = await esbuild.context(options);
  await ctx.watch();
  const { port } = await ctx.serve({ servedir: dist, host: '127.0.0.1', port: 5173 });
  console.log(`serving dist/ on http://127.0.0.1:${port}/`);
} else {
  await esbuild.build(options);
}
