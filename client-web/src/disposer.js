// Every listener, timer and resource registers its release here (Neuroglancer's RefCounted
// style): dispose() releases them all, once, in reverse order.
export class Disposer {
  #items = [];
  add(release) { this.#items.push(release); return release; }
  listen(target, type, fn, options) {
    target.addEventListener(type, fn, options);
    return this.add(() => target.removeEventListener(type, fn, options));
  }
  interval(fn, ms) { const id = setInterval(fn, ms); return this.add(() => clearInterval(id)); }
  dispose() { while (this.#items.length) this.#items.pop()(); }
  get size() { return this.#items.length; }  // releases held (tests check it stays flat across reconnects)
}
