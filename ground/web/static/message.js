// The message line in the header: the last reply for people, or an error in red.

export function showMessage(text, isError = false) {
  const out = document.getElementById("message");
  out.textContent = text;
  out.className = isError ? "error" : "";
  if (isError) console.warn(text);  // a warning, not an error: refusals are expected
}
