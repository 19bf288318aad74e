// CanMessage: a CAN message as the channels read and write it. A struct, as the manual's
// examples need: `new CanMessage[3]` gives three usable messages, `messages[0].Identifier = ...`
// changes the array's element.
using System;

namespace Ixxat.Vci3.Bal.Can
{
  public struct CanMessage
  {
    uint timeStamp, identifier;
    CanMsgFrameType frameType;
    byte dataLength, acceptReason;
    bool rtr, ext, srr, overrun;
    ulong data;  // the 8 data bytes, byte i in bits 8i..8i+7

    // Receive: the time stamp in ticks of the socket's time stamp counter. Transmit: the delay
    // in ticks of DelayedTXTimerDivisor / ClockFrequency before the message goes to the
    // controller (0: none).
    public uint TimeStamp { get { return timeStamp; } set { timeStamp = value; } }
    public uint Identifier { get { return identifier; } set { identifier = value; } }
    public CanMsgFrameType FrameType { get { return frameType; } set { frameType = value; } }
    // 0..8; the DLC, also on remote frames.
    public byte DataLength
    {
      get { return dataLength; }
      set
      {
        if (value > 8) throw new VciException(Native.E_INVALIDARG, "CanMessage.DataLength " + value + " is above 8");
        dataLength = value;
      }
    }
    public bool RemoteTransmissionRequest { get { return rtr; } set { rtr = value; } }
    public bool ExtendedFrameFormat { get { return ext; } set { ext = value; } }
    // Transmit: echo the message into this channel's receive FIFO once it was sent.
    // Receive: the message is such an echo.
    public bool SelfReceptionRequest { get { return srr; } set { srr = value; } }
    public bool PossibleOverrun { get { return overrun; } }
    public CanAcceptReason AcceptReason { get { return (CanAcceptReason)acceptReason; } }

    public byte this[int index]
    {
      get { CheckIndex(index); return (byte)(data >> (8 * index)); }
      set
      {
        CheckIndex(index);
        data = (data & ~(0xFFUL << (8 * index))) | ((ulong)value << (8 * index));
      }
    }

    static void CheckIndex(int index)
    {
      if (index < 0 || index > 7)
        throw new IndexOutOfRangeException("CanMessage data index " + index + " is not 0..7");
    }

    internal byte[] ToNative()
    {
      var b = new byte[Native.CanMsg2Size];
      Bytes.Put32(b, 0, timeStamp);
      Bytes.Put32(b, 8, identifier);
      b[12] = (byte)frameType;
      b[14] = (byte)((ext ? 0x80 : 0) | (rtr ? 0x40 : 0) | (srr ? 0x20 : 0) | (dataLength & 0x0F));
      for (int i = 0; i < 8; i++) b[16 + i] = (byte)(data >> (8 * i));
      return b;
    }

    internal static CanMessage FromNative(byte[] b)
    {
      var m = new CanMessage();
      m.timeStamp = Bytes.U32(b, 0);
      m.identifier = Bytes.U32(b, 8);
      m.frameType = (CanMsgFrameType)b[12];
      byte flags = b[14];
      m.dataLength = (byte)Math.Min(flags & 0x0F, 8);
      m.overrun = (flags & 0x10) != 0;
      m.srr = (flags & 0x20) != 0;
      m.rtr = (flags & 0x40) != 0;
      m.ext = (flags & 0x80) != 0;
      m.acceptReason = b[15];
      for (int i = 0; i < 8; i++) m.data |= (ulong)b[16 + i] << (8 * i);
      if (m.frameType == CanMsgFrameType.Error)
      {
        // libvcinpl2 numbers error codes as VCI 4 does (DLC 7, other 8); VCI 3 has other = 7.
        byte code = (byte)m.data;
        if (code == 8 || code == 7 || code == 5) m[0] = (byte)CanMsgError.Other;
      }
      return m;
    }

    public override string ToString()
    {
      var s = string.Format("{0} id=0x{1:X}{2}{3} dlc={4} [", frameType, identifier,
                            ext ? " ext" : "", rtr ? " rtr" : "", dataLength);
      for (int i = 0; i < Math.Min((int)dataLength, 8); i++) s += (i > 0 ? " " : "") + this[i].ToString("X2");
      return s + "] t=" + timeStamp;
    }
  }
}
