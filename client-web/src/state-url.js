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

// The page's query without the access token: a link to share or keep never carries it.
function searchWithoutToken() {
  const params = new URLSearchParams(location.search);
  params.delete('token');
  const s = params.toString();
  return s ? `?${s}` : '';
}

export function stateUrl(state) {
  const b64 = btoa(unescape(encodeURIComponent(JSON.stringify(state)))).replace(/\+/g, '-').replace(/\//g, '_').replace(/=+$/, '');
  return `${location.origin}${location.pathname}${searchWithoutToken()}#state=${b64}`;
}

// ?token=... on load: returns it (kept for this tab in sessionStorage) and removes it from the
// address bar and the history entry.
export function takeTokenFromUrl() {
  const token = new URLSearchParams(location.search).get('token');
  if (token === null) return '';
  sessionStorage.setItem('peakcast-token', token);
  history.replaceState(history.state, '', `${location.pathname}${searchWithoutToken()}${location.hash}`);
  return token;
}

let timer = 0;
export function writeState(state) {
  clearTimeout(timer);
  timer = setTimeout(() => history.replaceState(null, '', stateUrl(state)), 300);
}
