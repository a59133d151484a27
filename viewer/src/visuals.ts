// URDF visual meshes (the plan JSON's `links[].visuals`): STL, COLLADA and OBJ files loaded with
// three.js's loaders from the URLs `htngtp view` serves (`mesh/N.EXT` beside the plan). Each
// file is fetched and parsed once per scene; a link is drawn by its visuals once all of them
// have loaded, and keeps its collision shapes when one fails.

import * as THREE from 'three';
import { ColladaLoader } from 'three/addons/loaders/ColladaLoader.js';
import { OBJLoader } from 'three/addons/loaders/OBJLoader.js';
import { STLLoader } from 'three/addons/loaders/STLLoader.js';
import type { Color, Visual } from './plan';

/** A 1x1 white PNG: what a COLLADA file's textures load as (only mesh files are served). */
const BLANK_TEXTURE =
  'data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mP8/5+hHgAHggJ/PchI7wAAAABJRU5ErkJggg==';

/** Where a visual's file is: its `uri` relative to the plan's URL (or the page's). */
export function visualUrl(uri: string, base: string): string {
  return new URL(uri, new URL(base, location.href)).href;
}

/** Loads and parses visual mesh files, each URL once. */
export class VisualLoader {
  private readonly cache = new Map<string, Promise<THREE.Object3D>>();
  private readonly manager = new THREE.LoadingManager();

  constructor() {
    // Textures a COLLADA file names are not served: they load as a blank image, not a 404.
    this.manager.setURLModifier((url) => (/\.(dae|stl|obj)$/i.test(new URL(url, location.href).pathname) ? url : BLANK_TEXTURE));
  }

  /** The file's meshes, in the file's frame (a COLLADA file's unit applied, its up axis not). */
  load(url: string): Promise<THREE.Object3D> {
    let p = this.cache.get(url);
    if (p === undefined) {
      p = this.fetch(url);
      this.cache.set(url, p);
    }
    return p;
  }

  private async fetch(url: string): Promise<THREE.Object3D> {
    const ext = (/\.([a-z0-9]+)$/i.exec(new URL(url).pathname)?.[1] ?? '').toLowerCase();
    const res = await fetch(url, { cache: 'no-store' });
    if (!res.ok) throw new Error(`${url}: HTTP ${res.status}`);
    if (ext === 'stl') {
      const geometry = new STLLoader(this.manager).parse(await res.arrayBuffer());
      if (!geometry.attributes['normal']) geometry.computeVertexNormals();
      const mesh = new THREE.Mesh(geometry, new THREE.MeshStandardMaterial());
      mesh.userData['plain'] = true;
      return mesh;
    }
    const text = await res.text();
    if (ext === 'obj') {
      const group = new OBJLoader(this.manager).parse(text);
      group.traverse((o) => {
        if (o instanceof THREE.Mesh) o.userData['plain'] = true;
      });
      return group;
    }
    if (ext === 'dae') {
      const base = url.slice(0, url.lastIndexOf('/') + 1);
      const collada = new ColladaLoader(this.manager).parse(text, base);
      if (collada === null || collada.scene === undefined) throw new Error(`${url}: not a COLLADA document`);
      // As in ROS: the unit applies (the loader's scale), the up axis does not.
      collada.scene.rotation.set(0, 0, 0);
      return collada.scene;
    }
    throw new Error(`${url}: unknown mesh format ".${ext}" (expected .stl, .dae or .obj)`);
  }
}

/**
 * A visual placed in its link frame: a copy of the loaded file's meshes, at the visual's pose
 * and scale, in the URDF material's colour, or else the file's own colours (COLLADA), or else
 * `fallback` (STL and OBJ carry none). Returns the object and the materials it made.
 */
export function placeVisual(loaded: THREE.Object3D, v: Visual, fallback: Color): { object: THREE.Object3D; materials: THREE.Material[] } {
  const root = new THREE.Group();
  root.position.set(v.pose.t[0], v.pose.t[1], v.pose.t[2]);
  root.quaternion.set(v.pose.q[0], v.pose.q[1], v.pose.q[2], v.pose.q[3]);
  root.scale.set(v.scale[0], v.scale[1], v.scale[2]);
  const copy = loaded.clone(true);
  const materials: THREE.Material[] = [];
  copy.traverse((o) => {
    if (!(o instanceof THREE.Mesh)) return;
    const plain = o.userData['plain'] === true;
    if (v.color !== null || plain) {
      const c = v.color ?? fallback;
      const m = new THREE.MeshStandardMaterial({
        color: new THREE.Color(c[0], c[1], c[2]),
        roughness: 0.5,
        metalness: 0.1,
        side: THREE.DoubleSide,
      });
      materials.push(m);
      o.material = m;
    }
    o.castShadow = true;
    o.receiveShadow = true;
  });
  root.add(copy);
  return { object: root, materials };
}
