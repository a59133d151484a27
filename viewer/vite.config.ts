import { defineConfig } from 'vite';

// Relative asset paths: the built page works from any directory it is served from
// (`htngtp view` serves it at /, the browser tests too).
export default defineConfig({
  base: './',
  build: {
    outDir: 'dist',
    emptyOutDir: true,
    target: 'es2022',
    chunkSizeWarningLimit: 1000,
  },
});
