// A volume file dropped on the view goes to the server (POST /api/volumes) and is opened when it
// arrives: NRRD with its data attached, MetaImage .mha or TIFF, read by the server as any file.
// Progress shows in the volume panel; a refusal shows the server's reason.
export class DropUpload extends EventTarget {
  #xhr = null;

  constructor({ target, overlay, progress }, { token }, disposer) {
    super();
    this.progress = progress;
    this.token = token;
    let depth = 0;  // dragenter/dragleave fire for every child element
    const files = (e) => [...(e.dataTransfer?.items ?? [])].some((i) => i.kind === 'file');
    disposer.listen(target, 'dragenter', (e) => {
      if (!files(e)) return;
      e.preventDefault();
      depth++;
      overlay.hidden = false;
    });
    disposer.listen(target, 'dragover', (e) => { if (files(e)) e.preventDefault(); });
    disposer.listen(target, 'dragleave', () => { if (--depth <= 0) { depth = 0; overlay.hidden = true; } });
    disposer.listen(target, 'drop', (e) => {
      e.preventDefault();
      depth = 0;
      overlay.hidden = true;
      const file = e.dataTransfer?.files?.[0];
      // The refusal is shown in the volume panel; nothing more waits on it.
      if (file) this.upload(file).catch(() => {});
    });
    disposer.add(() => this.#xhr?.abort());
  }

  // Resolves with the new volume's info; rejects with the server's message.
  upload(file) {
    this.#xhr?.abort();
    const xhr = new XMLHttpRequest();
    this.#xhr = xhr;
    xhr.open('POST', `/api/volumes?name=${encodeURIComponent(file.name)}`);
    const token = this.token();
    if (token) xhr.setRequestHeader('Authorization', `Bearer ${token}`);
    xhr.upload.onprogress = (e) => {
      if (e.lengthComputable) this.progress.textContent = `uploading ${file.name}: ${Math.round((100 * e.loaded) / e.total)}%`;
    };
    this.progress.textContent = `uploading ${file.name}…`;
    return new Promise((resolve, reject) => {
      xhr.onload = () => {
        this.#xhr = null;
        let body = {};
        try { body = JSON.parse(xhr.responseText); } catch { /* not JSON: keep the status */ }
        if (xhr.status === 201) {
          this.progress.textContent = `uploaded ${file.name}: opening…`;
          this.dispatchEvent(new CustomEvent('uploaded', { detail: body }));
          resolve(body);
        } else {
          const why = body.message || `HTTP ${xhr.status}`;
          this.progress.textContent = `⚠ ${file.name}: ${why}`;
          reject(new Error(why));
        }
      };
      xhr.onerror = () => {
        this.#xhr = null;
        this.progress.textContent = `⚠ ${file.name}: the upload failed (refused before it was sent, or the connection broke)`;
        reject(new Error('upload failed'));
      };
      xhr.send(file);
    });
  }
}
