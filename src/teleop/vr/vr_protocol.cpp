#include "pmg/teleop/vr_protocol.hpp"

#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <vector>

namespace pmg::teleop {

namespace {

using Json = nlohmann::json;

constexpr std::uint32_t kKnownButtonBits = kVrButtonLower | kVrButtonUpper | kVrButtonThumbstick | kVrButtonMenu;
constexpr int kMaxDepth = 4;  // top object → hands array → hand object → p array

std::string fmt(const char* format, double a, double b = 0.0) {
  char buf[128];
  std::snprintf(buf, sizeof buf, format, a, b);
  return buf;
}

/// One failed check: reason + detail. The checker stops at the first failure.
struct Checker {
  VrReject reason = VrReject::kAccepted;
  std::string* detail = nullptr;

  bool fail(VrReject r, const std::string& key, const std::string& why) {
    if (reason == VrReject::kAccepted) {
      reason = r;
      if (detail != nullptr) *detail = key.empty() ? why : key + ": " + why;
    }
    return false;
  }

  /// Exactly the keys @p allowed (no unknown one, none missing).
  bool keys(const Json& obj, const std::string& where, std::initializer_list<const char*> allowed) {
    if (!obj.is_object()) return fail(VrReject::kWrongType, where, "expected an object");
    for (auto it = obj.begin(); it != obj.end(); ++it) {
      bool known = false;
      for (const char* k : allowed) known = known || it.key() == k;
      if (!known) {
        std::string list;
        for (const char* k : allowed) list += (list.empty() ? "" : ", ") + std::string(k);
        return fail(VrReject::kUnknownKey, where.empty() ? it.key() : where + "." + it.key(),
                    "unknown key (expected: " + list + ")");
      }
    }
    for (const char* k : allowed)
      if (!obj.contains(k)) return fail(VrReject::kMissingKey, where.empty() ? k : where + "." + k, "missing");
    return true;
  }

  bool number(const Json& v, const std::string& key, double lo, double hi, double& out) {
    if (!v.is_number()) return fail(VrReject::kWrongType, key, "expected a number");
    const double x = v.get<double>();
    if (!std::isfinite(x)) return fail(VrReject::kNonFinite, key, "not finite");
    if (x < lo || x > hi) return fail(VrReject::kOutOfRange, key, fmt("%g outside [%g, ", x, lo) + fmt("%g]", hi));
    out = x;
    return true;
  }

  template <std::size_t N>
  bool vector(const Json& v, const std::string& key, double lo, double hi, std::array<double, N>& out) {
    if (!v.is_array() || v.size() != N)
      return fail(VrReject::kWrongType, key, "expected an array of " + std::to_string(N) + " numbers");
    for (std::size_t i = 0; i < N; ++i)
      if (!number(v[i], key + "[" + std::to_string(i) + "]", lo, hi, out[i])) return false;
    return true;
  }

  /// Unit quaternion, x y z w; renormalised on success.
  bool quaternion(const Json& v, const std::string& key, std::array<double, 4>& q) {
    if (!vector(v, key, -2.0, 2.0, q)) return false;
    const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(std::abs(n - 1.0) <= kVrQuatNormTolerance))
      return fail(VrReject::kNotUnitQuaternion, key, fmt("norm %.6f, expected 1 ± %g", n, kVrQuatNormTolerance));
    for (double& c : q) c /= n;
    return true;
  }

  bool integer(const Json& v, const std::string& key, std::int64_t lo, std::int64_t hi, std::int64_t& out) {
    if (!v.is_number_integer()) return fail(VrReject::kWrongType, key, "expected an integer");
    if (v.is_number_unsigned()) {
      const auto u = v.get<std::uint64_t>();
      if (u > static_cast<std::uint64_t>(hi))
        return fail(VrReject::kOutOfRange, key, std::to_string(u) + " above " + std::to_string(hi));
      out = static_cast<std::int64_t>(u);
    } else {
      out = v.get<std::int64_t>();
    }
    if (out < lo || out > hi)
      return fail(VrReject::kOutOfRange, key,
                  std::to_string(out) + " outside [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return true;
  }
};

/// Parser callback state: duplicate keys and nesting depth (nlohmann keeps the last duplicate
/// silently, so it is caught while parsing).
struct ParseGuard {
  std::vector<std::vector<std::string>> objects;  // keys seen per open object (arrays: empty marker)
  std::vector<bool> is_object;
  bool duplicate = false;
  bool too_deep = false;
  std::string duplicate_key;
};

VrReject parseImpl(std::string_view text, VrSample& out, std::string* detail) {
  Checker c{VrReject::kAccepted, detail};
  if (text.size() > kVrMaxMessageBytes) {
    c.fail(VrReject::kTooLarge, "",
           std::to_string(text.size()) + " bytes, at most " + std::to_string(kVrMaxMessageBytes));
    return c.reason;
  }
  ParseGuard guard;
  const Json::parser_callback_t cb = [&guard](int /*depth*/, Json::parse_event_t event, Json& parsed) {
    switch (event) {
      case Json::parse_event_t::object_start:
      case Json::parse_event_t::array_start:
        guard.objects.emplace_back();
        guard.is_object.push_back(event == Json::parse_event_t::object_start);
        if (guard.objects.size() > static_cast<std::size_t>(kMaxDepth)) guard.too_deep = true;
        break;
      case Json::parse_event_t::object_end:
      case Json::parse_event_t::array_end:
        if (!guard.objects.empty()) {
          guard.objects.pop_back();
          guard.is_object.pop_back();
        }
        break;
      case Json::parse_event_t::key:
        if (!guard.objects.empty() && guard.is_object.back() && parsed.is_string()) {
          const auto& k = parsed.get_ref<const std::string&>();
          for (const std::string& seen : guard.objects.back())
            if (seen == k && !guard.duplicate) {
              guard.duplicate = true;
              guard.duplicate_key = k;
            }
          guard.objects.back().push_back(k);
        }
        break;
      case Json::parse_event_t::value:
        break;
    }
    return true;
  };
  const Json j = Json::parse(text.begin(), text.end(), cb, /*allow_exceptions=*/false);
  if (j.is_discarded()) {
    c.fail(VrReject::kBadJson, "", "not valid JSON");
    return c.reason;
  }
  if (!j.is_object()) {
    c.fail(VrReject::kNotObject, "", "expected a JSON object");
    return c.reason;
  }
  if (guard.too_deep) {
    c.fail(VrReject::kWrongType, "", "nested deeper than the protocol's " + std::to_string(kMaxDepth) + " levels");
    return c.reason;
  }
  if (guard.duplicate) {
    c.fail(VrReject::kDuplicateKey, guard.duplicate_key, "key given twice");
    return c.reason;
  }
  // "type" first, so that a future message kind is named as such rather than as unknown keys.
  const auto type = j.find("type");
  if (type == j.end()) {
    c.fail(VrReject::kMissingKey, "type", "missing");
    return c.reason;
  }
  if (!type->is_string()) {
    c.fail(VrReject::kWrongType, "type", "expected a string");
    return c.reason;
  }
  if (type->get_ref<const std::string&>() != "pose") {
    c.fail(VrReject::kUnknownType, "type",
           "'" + type->get_ref<const std::string&>().substr(0, 32) + "', expected 'pose'");
    return c.reason;
  }
  if (!c.keys(j, "", {"type", "frame", "t", "head", "hands"})) return c.reason;

  VrSample s;
  double t_ms = 0.0;
  if (!c.integer(j["frame"], "frame", 0, kVrMaxFrame, s.frame)) return c.reason;
  if (!c.number(j["t"], "t", 0.0, kVrMaxTimeMs, t_ms)) return c.reason;
  s.xr_time_us = std::llround(t_ms * 1000.0);

  const Json& head = j["head"];
  if (!c.keys(head, "head", {"p", "q"})) return c.reason;
  std::array<double, 3> p{};
  std::array<double, 4> q{};
  if (!c.vector(head["p"], "head.p", -kVrMaxPositionAbs, kVrMaxPositionAbs, p)) return c.reason;
  if (!c.quaternion(head["q"], "head.q", q)) return c.reason;
  s.head_position = webxrToV(p);
  s.head_quat = webxrQuatToV(q);

  const Json& hands = j["hands"];
  if (!hands.is_array() || hands.size() != 2) {
    c.fail(VrReject::kWrongType, "hands", "expected an array of 2 objects (left, right)");
    return c.reason;
  }
  for (std::size_t h = 0; h < 2; ++h) {
    const std::string where = "hands[" + std::to_string(h) + "]";
    const Json& hand = hands[h];
    if (!c.keys(hand, where, {"valid", "p", "q", "grip", "trigger", "buttons", "stick"})) return c.reason;
    if (!hand["valid"].is_boolean()) {
      c.fail(VrReject::kWrongType, where + ".valid", "expected true or false");
      return c.reason;
    }
    s.hand_valid[h] = hand["valid"].get<bool>();
    if (!c.vector(hand["p"], where + ".p", -kVrMaxPositionAbs, kVrMaxPositionAbs, p)) return c.reason;
    if (!c.quaternion(hand["q"], where + ".q", q)) return c.reason;
    s.hand_position[h] = webxrToV(p);
    s.hand_quat[h] = webxrQuatToV(q);
    if (!c.number(hand["grip"], where + ".grip", 0.0, 1.0, s.grip[h])) return c.reason;
    if (!c.number(hand["trigger"], where + ".trigger", 0.0, 1.0, s.trigger[h])) return c.reason;
    std::int64_t bits = 0;
    if (!c.integer(hand["buttons"], where + ".buttons", 0, 0xffffffffLL, bits)) return c.reason;
    if ((static_cast<std::uint64_t>(bits) & ~static_cast<std::uint64_t>(kKnownButtonBits)) != 0) {
      c.fail(VrReject::kUnknownButtonBits, where + ".buttons",
             std::to_string(bits) + " has bits outside VrButton (known bits: 0..15)");
      return c.reason;
    }
    s.buttons[h] = static_cast<std::uint32_t>(bits);
    std::array<double, 2> stick{};
    if (!c.vector(hand["stick"], where + ".stick", -1.0, 1.0, stick)) return c.reason;
    s.thumbstick[h] = {stick[0], stick[1] == 0.0 ? 0.0 : -stick[1]};
  }
  out = s;
  return VrReject::kAccepted;
}

bool finiteAll(const double* v, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i)
    if (!std::isfinite(v[i])) return false;
  return true;
}

}  // namespace

const char* toString(VrReject r) noexcept {
  switch (r) {
    case VrReject::kAccepted:
      return "accepted";
    case VrReject::kTooLarge:
      return "too_large";
    case VrReject::kBinaryFrame:
      return "binary_frame";
    case VrReject::kBadJson:
      return "bad_json";
    case VrReject::kDuplicateKey:
      return "duplicate_key";
    case VrReject::kNotObject:
      return "not_object";
    case VrReject::kUnknownType:
      return "unknown_type";
    case VrReject::kUnknownKey:
      return "unknown_key";
    case VrReject::kMissingKey:
      return "missing_key";
    case VrReject::kWrongType:
      return "wrong_type";
    case VrReject::kNonFinite:
      return "non_finite";
    case VrReject::kOutOfRange:
      return "out_of_range";
    case VrReject::kNotUnitQuaternion:
      return "not_unit_quaternion";
    case VrReject::kUnknownButtonBits:
      return "unknown_button_bits";
    case VrReject::kFrameNotIncreasing:
      return "frame_not_increasing";
    case VrReject::kRateLimited:
      return "rate_limited";
    case VrReject::kCount:
      break;
  }
  return "unknown";
}

std::array<double, 3> webxrToV(const std::array<double, 3>& p) noexcept { return {-p[2], -p[0], p[1]}; }

std::array<double, 4> webxrQuatToV(const std::array<double, 4>& q) noexcept {
  // Vector part (x, y, z) maps like a position; w is unchanged; order becomes w x y z.
  return {q[3], -q[2], -q[0], q[1]};
}

VrReject parseVrMessage(std::string_view text, VrSample& out, std::string* detail) noexcept {
  try {
    return parseImpl(text, out, detail);
  } catch (...) {  // std::bad_alloc (or a library surprise): refused, never escapes
    if (detail != nullptr) {
      try {
        *detail = "internal error while parsing";
      } catch (...) {
      }
    }
    return VrReject::kBadJson;
  }
}

pmg_lcm::vr_pose_t toVrPoseMessage(const VrSample& s, std::int64_t receive_utime) {
  pmg_lcm::vr_pose_t m{};
  m.utime = receive_utime;
  m.xr_time_us = s.xr_time_us;
  m.frame = s.frame;
  for (int i = 0; i < 3; ++i) m.head_position[i] = s.head_position[static_cast<std::size_t>(i)];
  for (int i = 0; i < 4; ++i) m.head_quat[i] = s.head_quat[static_cast<std::size_t>(i)];
  for (std::size_t h = 0; h < 2; ++h) {
    m.hand_valid[h] = s.hand_valid[h] ? 1 : 0;
    for (std::size_t i = 0; i < 3; ++i) m.hand_position[h][i] = s.hand_position[h][i];
    for (std::size_t i = 0; i < 4; ++i) m.hand_quat[h][i] = s.hand_quat[h][i];
    m.grip[h] = s.grip[h];
    m.trigger[h] = s.trigger[h];
    m.buttons[h] = static_cast<std::int32_t>(s.buttons[h]);
    m.thumbstick[h][0] = s.thumbstick[h][0];
    m.thumbstick[h][1] = s.thumbstick[h][1];
  }
  m.source = kVrSource;
  return m;
}

VrReject checkVrPoseMessage(const pmg_lcm::vr_pose_t& m, std::string* detail) noexcept {
  try {
    Checker c{VrReject::kAccepted, detail};
    const auto position = [&](const double* p, const char* key) {
      if (!finiteAll(p, 3)) return c.fail(VrReject::kNonFinite, key, "not finite");
      for (int i = 0; i < 3; ++i)
        if (std::abs(p[i]) > kVrMaxPositionAbs)
          return c.fail(VrReject::kOutOfRange, key, fmt("%g outside ±%g m", p[i], kVrMaxPositionAbs));
      return true;
    };
    const auto quat = [&](const double* q, const char* key) {
      if (!finiteAll(q, 4)) return c.fail(VrReject::kNonFinite, key, "not finite");
      const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
      if (!(std::abs(n - 1.0) <= kVrQuatNormTolerance))
        return c.fail(VrReject::kNotUnitQuaternion, key, fmt("norm %.6f", n));
      return true;
    };
    const auto unit = [&](double v, double lo, const char* key) {
      if (!std::isfinite(v)) return c.fail(VrReject::kNonFinite, key, "not finite");
      if (v < lo || v > 1.0) return c.fail(VrReject::kOutOfRange, key, fmt("%g outside [%g, 1]", v, lo));
      return true;
    };
    if (m.frame < 0 || m.xr_time_us < 0) return c.fail(VrReject::kOutOfRange, "frame/xr_time_us", "negative"), c.reason;
    if (!position(m.head_position, "head_position") || !quat(m.head_quat, "head_quat")) return c.reason;
    for (int h = 0; h < 2; ++h) {
      if (!position(m.hand_position[h], h == 0 ? "hand_position[0]" : "hand_position[1]") ||
          !quat(m.hand_quat[h], h == 0 ? "hand_quat[0]" : "hand_quat[1]") || !unit(m.grip[h], 0.0, "grip") ||
          !unit(m.trigger[h], 0.0, "trigger") || !unit(m.thumbstick[h][0], -1.0, "thumbstick") ||
          !unit(m.thumbstick[h][1], -1.0, "thumbstick"))
        return c.reason;
      if ((static_cast<std::uint32_t>(m.buttons[h]) & ~kKnownButtonBits) != 0)
        return c.fail(VrReject::kUnknownButtonBits, "buttons", std::to_string(m.buttons[h])), c.reason;
    }
    if (m.source.size() > 63) return c.fail(VrReject::kOutOfRange, "source", "longer than 63 bytes"), c.reason;
    return VrReject::kAccepted;
  } catch (...) {
    return VrReject::kBadJson;
  }
}

}  // namespace pmg::teleop
