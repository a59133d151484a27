// three.js objects for a plan's scene: one group per object and per agent link, built from the
// contract's shapes (box, cylinder with axis z, capsule between two points, triangle mesh), and
// posed from `Pose`s. World frame: z up, metres.

import * as THREE from 'three';
import { CSS2DObject } from 'three/addons/renderers/CSS2DRenderer.js';
import type { Color, Plan, Pose, Shape, Visual } from './plan';
import type { WorldState } from './timeline';
import { VisualLoader, placeVisual, visualUrl } from './visuals';

const DEFAULT_OBJECT_COLOR: Color = [0.7, 0.7, 0.7];
const DEFAULT_ROBOT_COLOR: Color = [0.8, 0.8, 0.82];
const DEFAULT_HUMAN_COLOR: Color = [0.85, 0.7, 0.6];
const HIGHLIGHT = new THREE.Color(0xffb000);

/** How the links' visual meshes are doing (the browser tests read it). */
export interface VisualStats {
  /** Links with visuals whose files are still loading. */
  pending: number;
  /** Links drawn by their visuals. */
  links: number;
  /** three.js meshes in the loaded visuals. */
  meshes: number;
  /** Links kept on their collision shapes because a visual failed, with why. */
  failed: string[];
}

/** The built scene: groups by name, so that states can be applied and read back. */
export class SceneView {
  readonly root = new THREE.Group();
  readonly objectsGroup = new THREE.Group();
  readonly agentsGroup = new THREE.Group();
  readonly objects = new Map<string, THREE.Group>();
  readonly links = new Map<string, Map<string, THREE.Group>>();
  private readonly materials: THREE.MeshStandardMaterial[] = [];
  private readonly geometries: THREE.BufferGeometry[] = [];
  private readonly labels: CSS2DObject[] = [];
  private highlighted = new Set<string>();
  private readonly visualLoader = new VisualLoader();
  private readonly loadedFiles: Promise<THREE.Object3D>[] = [];
  private disposed = false;
  readonly visualStats: VisualStats = { pending: 0, links: 0, meshes: 0, failed: [] };

  /**
   * `base`: the plan's URL, against which the links' visual meshes are loaded (null: draw links
   * by their collision shapes only); `onChange` is called when a link's drawing changes.
   */
  constructor(plan: Plan, base: string | null = null, private readonly onChange: () => void = () => {}) {
    this.root.name = 'plan';
    this.objectsGroup.name = 'objects';
    this.agentsGroup.name = 'agents';
    this.root.add(this.objectsGroup, this.agentsGroup);

    for (const o of plan.scene.objects) {
      const g = new THREE.Group();
      g.name = o.name;
      const body = new THREE.Group();
      for (const part of o.parts) {
        const mesh = this.mesh(part.shape, part.color ?? o.color ?? DEFAULT_OBJECT_COLOR, o.movable);
        applyPose(mesh, part.pose);
        body.add(mesh);
      }
      // The label floats above the object's top, in the object's frame (body not yet posed).
      const top = o.parts.length > 0 ? new THREE.Box3().setFromObject(body).max.z : 0;
      g.add(body);
      g.userData = { movable: o.movable };
      applyPose(g, o.pose);
      this.label(g, o.name, top + 0.06, o.movable ? 'label movable' : 'label');
      this.objectsGroup.add(g);
      this.objects.set(o.name, g);
    }
    for (const a of plan.scene.agents) {
      const agentGroup = new THREE.Group();
      agentGroup.name = a.name;
      const byLink = new Map<string, THREE.Group>();
      const fallback = a.kind === 'human' ? DEFAULT_HUMAN_COLOR : DEFAULT_ROBOT_COLOR;
      for (const l of a.links) {
        const g = new THREE.Group();
        g.name = `${a.name}/${l.name}`;
        const collision = new THREE.Group();
        collision.name = 'collision';
        for (const s of l.shapes) {
          const m = this.mesh(s.shape, s.color ?? fallback, true);
          applyPose(m, s.pose);
          collision.add(m);
        }
        g.add(collision);
        if (base !== null && l.visuals.length > 0) {
          this.loadVisuals(g, collision, l.visuals, base, l.shapes[0]?.color ?? fallback);
        }
        applyPose(g, a.link_poses[l.name]!);
        agentGroup.add(g);
        byLink.set(l.name, g);
      }
      // The agent's name floats above its highest link.
      const labelLink = a.eye_link ?? a.links[0]?.name;
      const anchor = labelLink === undefined ? undefined : byLink.get(labelLink);
      if (anchor !== undefined) {
        const lbl = this.label(new THREE.Group(), a.name, 0, `label agent ${a.kind}`);
        lbl.userData = { follow: anchor };
        agentGroup.add(lbl.parent!);
      }
      this.agentsGroup.add(agentGroup);
      this.links.set(a.name, byLink);
    }
  }

  /** Draws link `g` by its visuals once they all load; on a failure it keeps `collision`. */
  private loadVisuals(g: THREE.Group, collision: THREE.Group, visuals: Visual[], base: string, fallback: Color): void {
    this.visualStats.pending++;
    const files = visuals.map((v) => {
      const p = this.visualLoader.load(visualUrl(v.uri, base));
      this.loadedFiles.push(p);
      return p;
    });
    Promise.all(files)
      .then((loaded) => {
        if (this.disposed) return;
        const group = new THREE.Group();
        group.name = 'visual';
        loaded.forEach((file, i) => {
          const { object, materials } = placeVisual(file, visuals[i]!, fallback);
          this.materials.push(...(materials as THREE.MeshStandardMaterial[]));
          group.add(object);
        });
        let meshes = 0;
        group.traverse((o) => {
          if (o instanceof THREE.Mesh) meshes++;
        });
        g.add(group);
        collision.visible = false;
        this.visualStats.links++;
        this.visualStats.meshes += meshes;
      })
      .catch((e: unknown) => {
        if (this.disposed) return;
        const why = `${g.name}: ${e instanceof Error ? e.message : String(e)}`;
        this.visualStats.failed.push(why);
        console.warn(`visual mesh not shown, the link is drawn by its collision shapes: ${why}`);
      })
      .finally(() => {
        this.visualStats.pending--;
        if (!this.disposed) this.onChange();
      });
  }

  private label(parent: THREE.Object3D, text: string, z: number, cls: string): CSS2DObject {
    const div = document.createElement('div');
    div.className = cls;
    div.textContent = text;
    const obj = new CSS2DObject(div);
    obj.position.set(0, 0, z);
    obj.center.set(0.5, 1);
    parent.add(obj);
    this.labels.push(obj);
    return obj;
  }

  private mesh(shape: Shape, color: Color, small: boolean): THREE.Mesh {
    const geometry = geometryOf(shape);
    this.geometries.push(geometry);
    const material = new THREE.MeshStandardMaterial({
      color: new THREE.Color(color[0], color[1], color[2]),
      roughness: small ? 0.55 : 0.8,
      metalness: 0.05,
      flatShading: 'mesh' in shape || 'box' in shape,
    });
    this.materials.push(material);
    const mesh = new THREE.Mesh(geometry, material);
    mesh.castShadow = true;
    mesh.receiveShadow = true;
    return mesh;
  }

  /** Moves every object and link to the state's poses; highlights the named objects. */
  apply(state: WorldState, highlight: Set<string>): void {
    for (const [name, pose] of state.objects) {
      const g = this.objects.get(name);
      if (g !== undefined) applyPose(g, pose);
    }
    for (const [agent, poses] of state.links) {
      const byLink = this.links.get(agent);
      if (byLink === undefined) continue;
      for (const [name, pose] of poses) {
        const g = byLink.get(name);
        if (g !== undefined) applyPose(g, pose);
      }
    }
    for (const lbl of this.labels) {
      const follow = lbl.userData['follow'] as THREE.Object3D | undefined;
      if (follow !== undefined) lbl.position.copy(follow.position).add(new THREE.Vector3(0, 0, 0.35));
    }
    if (!sameSet(highlight, this.highlighted)) {
      for (const [name, g] of this.objects) {
        const on = highlight.has(name);
        g.traverse((o) => {
          if (o instanceof THREE.Mesh && o.material instanceof THREE.MeshStandardMaterial) {
            o.material.emissive.copy(on ? HIGHLIGHT : new THREE.Color(0));
            o.material.emissiveIntensity = on ? 0.35 : 0;
          }
          if (o instanceof CSS2DObject) o.element.classList.toggle('active', on);
        });
      }
      this.highlighted = new Set(highlight);
    }
  }

  /** The rendered pose of an object (what the page shows), or null for an unknown name. */
  objectPose(name: string): Pose | null {
    const g = this.objects.get(name);
    return g === undefined ? null : poseOf(g);
  }

  linkPose(agent: string, link: string): Pose | null {
    const g = this.links.get(agent)?.get(link);
    return g === undefined ? null : poseOf(g);
  }

  get linkCount(): number {
    let n = 0;
    for (const m of this.links.values()) n += m.size;
    return n;
  }

  dispose(): void {
    this.disposed = true;
    for (const p of this.loadedFiles) {
      p.then(
        (o) =>
          o.traverse((m) => {
            if (!(m instanceof THREE.Mesh)) return;
            (m.geometry as THREE.BufferGeometry).dispose();
            for (const mat of Array.isArray(m.material) ? m.material : [m.material]) (mat as THREE.Material).dispose();
          }),
        () => {},
      );
    }
    this.root.removeFromParent();
    for (const l of this.labels) l.element.remove();
    for (const g of this.geometries) g.dispose();
    for (const m of this.materials) m.dispose();
  }
}

export function applyPose(o: THREE.Object3D, p: Pose): void {
  o.position.set(p.t[0], p.t[1], p.t[2]);
  o.quaternion.set(p.q[0], p.q[1], p.q[2], p.q[3]);
}

function poseOf(o: THREE.Object3D): Pose {
  return {
    t: [o.position.x, o.position.y, o.position.z],
    q: [o.quaternion.x, o.quaternion.y, o.quaternion.z, o.quaternion.w],
  };
}

function sameSet(a: Set<string>, b: Set<string>): boolean {
  if (a.size !== b.size) return false;
  for (const x of a) if (!b.has(x)) return false;
  return true;
}

/** Geometry of a shape in its own frame (three.js cylinders and capsules run along y: turned to z). */
export function geometryOf(shape: Shape): THREE.BufferGeometry {
  if ('box' in shape) {
    const [x, y, z] = shape.box.half_extents;
    return new THREE.BoxGeometry(2 * x, 2 * y, 2 * z);
  }
  if ('cylinder' in shape) {
    const { radius, half_height } = shape.cylinder;
    const g = new THREE.CylinderGeometry(radius, radius, 2 * half_height, 40);
    g.rotateX(Math.PI / 2);
    return g;
  }
  if ('capsule' in shape) {
    const { a, b, radius } = shape.capsule;
    const va = new THREE.Vector3(...a);
    const vb = new THREE.Vector3(...b);
    const axis = vb.clone().sub(va);
    const length = axis.length();
    const g = new THREE.CapsuleGeometry(radius, length, 8, 20);
    if (length > 1e-9) {
      g.applyQuaternion(new THREE.Quaternion().setFromUnitVectors(new THREE.Vector3(0, 1, 0), axis.normalize()));
    }
    const mid = va.add(vb).multiplyScalar(0.5);
    g.translate(mid.x, mid.y, mid.z);
    return g;
  }
  const { vertices, triangles } = shape.mesh;
  // Non-indexed, so that computed normals are per face: furniture edges stay crisp.
  const pos = new Float32Array(triangles.length * 9);
  triangles.forEach((tri, i) => {
    for (let k = 0; k < 3; k++) {
      const v = vertices[tri[k]!]!;
      pos.set(v, i * 9 + k * 3);
    }
  });
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(pos, 3));
  g.computeVertexNormals();
  return g;
}
