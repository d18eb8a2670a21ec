// Shareable state: volume, camera, TF and render settings in the URL fragment (base64url JSON),
// restored on load; the fragment never reaches the server's logs.
export function readState() {
  const m = location.hash.match(/state=([A-Za-z0-9_-]+)/);
  if (!m) return null;
  try {
    const b64 = m[1].replace(/-/g, '+').replace(/_/g, '/');
    return JSON.parse(decodeURIComponent(escape(atob(b64))));
  } catch {
    return null;
  }
}

export function stateUrl(state) {
  const b64 = btoa(unescape(encodeURIComponent(JSON.stringify(state)))).replace(/\+/g, '-').replace(/\//g, '_').replace(/=+$/, '');
  return `${location.origin}${location.pathname}${location.search}#state=${b64}`;
}

let timer = 0;
export function writeState(state) {
  clearTimeout(timer);
  timer = setTimeout(() => history.replaceState(null, '', stateUrl(state)), 300);
}
