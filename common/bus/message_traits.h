#pragma once
// What the bus needs to know of a message type; specialised by the generated code in
// build/generated/rslam/msg/*.h for every top-level message of idl/.

namespace rslam::bus {

template <class T>
struct MessageTraits;  // kTypeName ("rslam::msg::Image"), kKeyed, kIdl (self-contained IDL text)

template <class T>
concept Message = requires { MessageTraits<T>::kTypeName; };

}  // namespace rslam::bus
