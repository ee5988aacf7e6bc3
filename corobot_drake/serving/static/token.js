// The server's bearer token (docs/services.md, "Security"). A server off loopback prints the
// dashboard's URL with the token in its fragment (#token=...), which the browser never sends
// to a server; the page keeps it for this tab and sends it as `Authorization: Bearer` on every
// request it makes. Without one (a loopback server), requests go as they are.
"use strict";

const corobotToken = (() => {
  const match = /(?:^#|&)token=([^&]*)/.exec(location.hash);
  if (match) sessionStorage.setItem("corobot-token", decodeURIComponent(match[1]));
  return sessionStorage.getItem("corobot-token");
})();

// `fetch` options with the token's header added.
function authorized(init = {}) {
  if (!corobotToken) return init;
  return { ...init, headers: { ...(init.headers || {}), Authorization: `Bearer ${corobotToken}` } };
}

// A page's URL carrying the token on to it (a link cannot send a header).
function withToken(url) {
  return corobotToken ? `${url}#token=${encodeURIComponent(corobotToken)}` : url;
}
